#!/usr/bin/env python3
"""compare-outputs.py A B: compares two folders written by scripts/capture-outputs.sh (two builds
of mbi on the same scenes). Numbers in text files (OBJ, VTK, point lists) and in the JSON files
(measurements excluded: keys ending in _ms, timings_ms, seconds, rss_kb, scene_file) must agree within 1e-12
relative (absolute below 1); PC2 caches are compared as float32; any other file byte for byte.
Exit 0 when everything agrees."""
import json, os, re, struct, sys
A, B = sys.argv[1], sys.argv[2]
TOL = 1e-12
worst = [0.0, '']
bad = []
def close(x, y, where):
    d = abs(x - y) / max(1.0, abs(x), abs(y))
    if d > worst[0]: worst[0], worst[1] = d, where
    if d > TOL: bad.append(f'{where}: {x} vs {y}')
def walk_json(a, b, where):
    if isinstance(a, dict):
        ka = {k for k in a if not (k.endswith('_ms') or k in ('timings_ms', 'seconds', 'rss_kb', 'scene_file'))}
        kb = {k for k in b if not (k.endswith('_ms') or k in ('timings_ms', 'seconds', 'rss_kb', 'scene_file'))}
        if ka != kb: bad.append(f'{where}: keys differ {sorted(ka ^ kb)}')
        for k in ka & kb: walk_json(a[k], b[k], where + '/' + k)
    elif isinstance(a, list):
        if len(a) != len(b): bad.append(f'{where}: length {len(a)} vs {len(b)}'); return
        for i, (x, y) in enumerate(zip(a, b)): walk_json(x, y, f'{where}[{i}]')
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)) and not isinstance(a, bool):
        close(float(a), float(b), where)
    elif a != b: bad.append(f'{where}: {a!r} vs {b!r}')
num = re.compile(rb'^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$')
def text_cmp(pa, pb, rel):
    ta, tb = open(pa, 'rb').read().split(), open(pb, 'rb').read().split()
    if len(ta) != len(tb): bad.append(f'{rel}: token count {len(ta)} vs {len(tb)}'); return
    for i, (x, y) in enumerate(zip(ta, tb)):
        if x == y: continue
        if num.match(x) and num.match(y): close(float(x), float(y), f'{rel} token {i}')
        else: bad.append(f'{rel} token {i}: {x!r} vs {y!r}'); return
files = 0
for root, _, names in os.walk(A):
    for n in sorted(names):
        pa = os.path.join(root, n); rel = os.path.relpath(pa, A); pb = os.path.join(B, rel)
        if n.endswith(('.stdout', '.stderr')): continue
        if not os.path.exists(pb): bad.append(f'{rel}: missing in B'); continue
        files += 1
        da, db = open(pa, 'rb').read(), open(pb, 'rb').read()
        if da == db: continue
        if n.endswith('.json'): walk_json(json.loads(da), json.loads(db), rel)
        elif n.endswith(('.obj', '.vtk', '.txt', '.node', '.ele', '.off')): text_cmp(pa, pb, rel)
        elif n.endswith('.pc2') and len(da) == len(db):
            fa = struct.unpack(f'<{(len(da)-32)//4}f', da[32:]); fb = struct.unpack(f'<{(len(db)-32)//4}f', db[32:])
            for i, (x, y) in enumerate(zip(fa, fb)):
                if x != y: close(x, y, f'{rel} float {i}')
        else: bad.append(f'{rel}: bytes differ')
for root, _, names in os.walk(B):
    for n in names:
        rel = os.path.relpath(os.path.join(root, n), B)
        if not n.endswith(('.stdout', '.stderr')) and not os.path.exists(os.path.join(A, rel)): bad.append(f'{rel}: only in B')
print(f'{files} files compared; worst relative difference {worst[0]:.3g} at {worst[1]}')
for b in bad[:30]: print('  DIFF', b)
print('EQUAL within 1e-12' if not bad else f'{len(bad)} differences')
sys.exit(1 if bad else 0)

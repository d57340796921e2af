#!/usr/bin/env python3
"""Log-log plot of the scale report's tables (bench/results/scale.md): precompute and solve
against control vertices for each cage family, the simulator's step against tetrahedra, and
embedding and evaluation against dense points.

    /usr/bin/python3 bench/plot_scale.py [bench/results/scale.md] [bench/results/scale.png]

Reads the tables as the report writes them (a section's first table, by its column names), so
the picture always shows the figures the report states.
"""
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def number(cell):
    """'1,078' -> 1078, '0.6M (0.8M)' -> 0.6e6, '1M' -> 1e6, '9.06 GiB' -> 9.06."""
    m = re.match(r"\s*([0-9][0-9,]*\.?[0-9]*(?:e[+-]?[0-9]+)?)\s*([KM])?", cell)
    if not m:
        raise ValueError(f"not a number: {cell!r}")
    scale = {"K": 1e3, "M": 1e6, None: 1.0}[m.group(2)]
    return float(m.group(1).replace(",", "")) * scale


def tables(text):
    """{section title: (header, rows)} for the first table under each '##' or '###' title."""
    found, title, lines = {}, None, text.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("#"):
            title = line.lstrip("#").strip()
        elif line.startswith("|") and title and title not in found and i + 1 < len(lines) \
                and lines[i + 1].startswith("|---"):
            header = [c.strip() for c in line.strip("|").split("|")]
            rows = []
            for row in lines[i + 2:]:
                if not row.startswith("|"):
                    break
                rows.append([c.strip() for c in row.strip("|").split("|")])
            found[title] = (header, rows)
    return found


def column(table, name, cast=number):
    header, rows = table
    k = next(i for i, h in enumerate(header) if h.startswith(name))
    return [cast(r[k]) for r in rows]


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "bench/results/scale.md"
    out = sys.argv[2] if len(sys.argv) > 2 else "bench/results/scale.png"
    t = tables(open(src, encoding="utf-8").read())
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(15, 4.5))
    for title, marker in (("Voxel shell", "o"), ("TetGen shell", "s"), ("Solid box", "^")):
        key = next(k for k in t if k.startswith(title))
        n = column(t[key], "control vertices")
        a.loglog(n, column(t[key], "precompute s"), marker + "-", label=f"precompute (s), {title.lower()}")
        a.loglog(n, [v / 1e3 for v in column(t[key], "solve ms")], marker + "--", label=f"solve (s), {title.lower()}")
    a.set_xlabel("control vertices")
    a.set_ylabel("seconds")
    a.set_title("modified-BI: precompute and solve")
    sim = t["The simulator's step against size"]
    b.loglog(column(sim, "tetrahedra"), column(sim, "step ms"), "o-", label="step")
    b.loglog(column(sim, "tetrahedra"), column(sim, "solve ms"), "s--", label="PCG solve")
    b.loglog(column(sim, "tetrahedra"), column(sim, "assembly ms"), "^--", label="assembly")
    b.set_xlabel("tetrahedra")
    b.set_ylabel("ms")
    b.set_title("simulator step (PCG, 1e-6)")
    pts = t["1M and 10M dense points"]
    for tets in sorted(set(column(pts, "tetrahedra"))):
        rows = [r for r in pts[1] if number(r[1]) == tets]
        sub = (pts[0], rows)
        p = column(sub, "points")
        c.loglog(p, column(sub, "embed ms"), "o-", label=f"embed, {int(tets):,} tets")
        c.loglog(p, column(sub, "evaluate ms, by element"), "s--", label=f"evaluate by element, {int(tets):,} tets")
    c.set_xlabel("dense points")
    c.set_ylabel("ms")
    c.set_title("embedding and evaluation (float)")
    for ax in (a, b, c):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"plot_scale.py: wrote {out}")


if __name__ == "__main__":
    main()

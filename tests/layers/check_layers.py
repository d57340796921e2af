#!/usr/bin/env python3
"""The layers of mbi, checked from the source: every #include of a library, door or test may reach
only its own target and the targets below it (README "Layout"). Exit 1 with one line per
include that reaches up or sideways, naming the file and line.

    python3 tests/layers/check_layers.py [SOURCE_DIR]
"""
import pathlib
import re
import sys

# target -> the targets it builds on directly (bottom up); below() closes this transitively.
GRAPH = {
    "base": [],
    "interp": ["base"], "sim": ["base"], "io": ["base"],
    "pipeline": ["interp", "sim"], "generate": ["io", "interp"], "raster": ["io"],
    "interact": ["pipeline"],
    "gpu": ["pipeline", "raster", "io"],
    "scene_format": ["generate", "pipeline"], "scenes": ["gpu", "scene_format"],
    "viewer": ["scenes", "interact"], "web": ["scene_format", "interact"], "python": ["scenes"], "bench": ["scenes"],
    "app": ["viewer", "scenes"],
}
# source folder -> target (the longest matching prefix wins)
FOLDERS = {
    "base": "base", "interp": "interp", "sim": "sim", "io": "io", "pipeline": "pipeline",
    "generate": "generate", "gpu/raster": "raster", "gpu/gl": "gpu", "scenes": "scenes",
    "scenes/format": "scene_format",
    "viewer": "viewer", "web": "web", "python": "python", "bench": "bench", "app": "app",
    "interact": "interact",
}
# public header prefix (<mbi/X/...>, or <mbi/X/Y> for a header of a folder's second target) -> target
HEADERS = {"base": "base", "error.hpp": "base", "interp": "interp", "interp.hpp": "interp",
           "sim": "sim", "io": "io", "pipeline": "pipeline", "generate": "generate",
           "raster": "raster", "gpu": "gpu", "scenes": "scenes", "viewer": "viewer", "web": "web",
           "interact": "interact", "scenes/scene.hpp": "scene_format",
           "scenes/model_scene.hpp": "scene_format", "scenes/models.hpp": "scene_format",
           "scenes/limits.hpp": "scene_format"}
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')


def below(target):
    seen, todo = {target}, [target]
    while todo:
        for dep in GRAPH[todo.pop()]:
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return seen


def owner(rel):
    """The target a file belongs to (tests/X/... as X), or None for files outside the layers."""
    parts = rel.parts[1:] if rel.parts[0] == "tests" else rel.parts
    path = "/".join(parts)
    best = None
    for folder, target in FOLDERS.items():
        if (path + "/").startswith(folder + "/") and (best is None or len(folder) > len(best[0])):
            best = (folder, target)
    return best[1] if best else None


def check(root):
    problems, files = [], 0
    for f in sorted(root.rglob("*")):
        if f.suffix not in (".cpp", ".hpp", ".h") or not f.is_file():
            continue
        rel = f.relative_to(root)
        if rel.parts[0] in ("build", "node_modules") or "node_modules" in rel.parts:
            continue
        target = owner(rel)
        if target is None:
            continue
        files += 1
        allowed = below(target)
        for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m:
                continue
            kind, name = m.groups()
            if kind == '"' and ".." in pathlib.PurePosixPath(name).parts:
                problems.append(f"{rel}:{n}: #include \"{name}\" reaches out of its folder")
            if kind == "<" and name.startswith("mbi/"):
                parts = name.split("/")
                reached = HEADERS.get("/".join(parts[1:3]), HEADERS.get(parts[1]))
                if reached is None:
                    problems.append(f"{rel}:{n}: <{name}> belongs to no target")
                elif reached not in allowed:
                    problems.append(f"{rel}:{n}: {target} includes <{name}> of {reached}, "
                                    f"which is not below it")
    return files, problems


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
    missing = [folder for folder in FOLDERS if not (root / folder).is_dir()]
    if missing:
        print(f"check_layers: the tree lacks the folders {', '.join(missing)}", file=sys.stderr)
        return 1
    files, problems = check(root)
    for p in problems:
        print(p)
    print(f"check_layers: {files} files, {len(problems)} includes across the layers")
    return 1 if problems or files == 0 else 0


if __name__ == "__main__":
    sys.exit(main())

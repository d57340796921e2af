#!/usr/bin/env python3
"""The test numbers of the sanitizer pass (scripts/test.sh --sanitizers), for ctest -I.

    ctest --preset debug --show-only=json-v1 | python3 scripts/ctest_lists.py

Prints one line, two lists: the tests that may make OpenGL contexts (run with LeakSanitizer off,
Mesa's driver leaks) and all the others. The Catch2 cases tagged [long] are in neither.
"""
import json
import os
import subprocess
import sys

GL_PROGRAMS = {"test_gpu", "test_scenes", "test_app", "test_viewer"}


def long_cases(tests):
    """The names of the cases tagged [long] in every Catch2 program (test_*) the tests run."""
    programs = {t["command"][0] for t in tests
                if t.get("command") and os.path.basename(t["command"][0]).startswith("test_")}
    names = set()
    for program in programs:
        listed = subprocess.run([program, "--list-test-names-only", "[long]"], capture_output=True,
                                text=True)
        if listed.returncode < 0:  # Catch2 exits with the number of cases listed; a signal is a failure
            sys.exit(f"{program} --list-test-names-only: killed by signal {-listed.returncode}")
        names.update(n.strip() for n in listed.stdout.splitlines() if n.strip())
    return names


def uses_gl(test):
    cmd = test.get("command") or ["?"]
    if os.path.basename(cmd[0]) in GL_PROGRAMS:
        return True
    # bad-input cases: mbi run / view without --gpu off may make a context
    args = [a[len("-DARGS="):] for a in cmd if a.startswith("-DARGS=")]
    return bool(args) and args[0].split(";")[0] in ("run", "view") and "--gpu;off" not in args[0]


def main():
    tests = json.load(sys.stdin)["tests"]
    long = long_cases(tests)
    kept = [(i + 1, t) for i, t in enumerate(tests) if t["name"] not in long]
    gl = [n for n, t in kept if uses_gl(t)]
    rest = [n for n, t in kept if not uses_gl(t)]
    # ctest -I reads start,end,stride and then single numbers; there is no test 0, so only those count
    print(",".join(map(str, [0, 0, 0] + gl)), ",".join(map(str, [0, 0, 0] + rest)))


if __name__ == "__main__":
    main()

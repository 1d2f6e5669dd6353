#!/usr/bin/env python3
"""Checks the library's layering: every #include <s2kf/X/...> in include/s2kf/Y/ must be allowed by
the dependency table of docs/architecture.md (section "Layers"), so the table and the code cannot
drift apart. Exits 1 naming each forbidden arrow."""
import pathlib
import re
import sys

def self_test():
    """The check must fail on a forbidden arrow and pass without it (a check that cannot fail is none)."""
    import subprocess
    import tempfile
    with tempfile.TemporaryDirectory() as scratch:
        tree = pathlib.Path(scratch)
        (tree / "docs").mkdir()
        (tree / "docs" / "architecture.md").write_text("| `core` | | |\n| `body` | `core` | |\n")
        for folder in ("core", "body"):
            (tree / "include" / "s2kf" / folder).mkdir(parents=True)
        (tree / "include" / "s2kf" / "body" / "b.hpp").write_text("#include <s2kf/core/a.hpp>\n")
        (tree / "include" / "s2kf" / "core" / "a.hpp").write_text("#include <vector>\n")
        allowed = subprocess.run([sys.executable, __file__, scratch], capture_output=True).returncode
        (tree / "include" / "s2kf" / "core" / "a.hpp").write_text("#include <s2kf/body/b.hpp>\n")
        forbidden = subprocess.run([sys.executable, __file__, scratch], capture_output=True).returncode
    if (allowed, forbidden) != (0, 1):
        sys.exit(f"self-test failed: allowed tree exit {allowed}, forbidden arrow exit {forbidden}")


if len(sys.argv) > 1 and sys.argv[1] == "--self-test":
    self_test()
    sys.argv = sys.argv[:1]
root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[2])
table = {}
for line in (root / "docs" / "architecture.md").read_text().splitlines():
    # | `track` | `core`, `body`, ... | ... |
    m = re.match(r"^\| `(\w+)` \| ([^|]*)\|", line)
    if m:
        table[m.group(1)] = set(re.findall(r"`(\w+)`", m.group(2)))
if not table:
    sys.exit("docs/architecture.md has no dependency table (rows like | `track` | `core`, `body` |)")

problems = []
folders = sorted(p.name for p in (root / "include" / "s2kf").iterdir() if p.is_dir())
for folder in folders:
    if folder not in table:
        problems.append(f"include/s2kf/{folder}/ has no row in the dependency table")
        continue
    for header in sorted((root / "include" / "s2kf" / folder).glob("*.h*")):
        for number, line in enumerate(header.read_text().splitlines(), 1):
            m = re.match(r"\s*#\s*include\s*<s2kf/(\w+)/", line)
            if m and m.group(1) != folder and m.group(1) not in table[folder]:
                problems.append(f"{header.relative_to(root)}:{number}: {folder} may not include {m.group(1)}")
for p in problems:
    print(p)
print(f"{len(folders)} folders checked against the table, {len(problems)} forbidden arrows")
sys.exit(1 if problems else 0)

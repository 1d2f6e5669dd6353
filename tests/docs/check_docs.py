#!/usr/bin/env python3
"""Checks the Markdown pages of the repository (README.md, CHANGELOG.md, docs/**/*.md).

links:   every relative link points to a file or folder that exists and, with #anchor, to a
         heading of that page (GitHub's anchors: lower case, punctuation dropped, spaces to -).
length:  no page is longer than 500 lines; CHANGELOG.md is left out: it gains an entry with every
         change, and its history is not cut to fit.
dates:   no page dates a fact by a "session" (an ordinal, "this", "that" and the like before it).
paths:   every repository path a page names in backticks (`include/...`, `tests/...`, ...) exists;
         the dated notes under docs/notes/ and CHANGELOG.md are left out, as they name the files
         of their day.
--self-test runs each check on a scratch tree with one fault of its kind and fails unless the
check finds it.

Usage: check_docs.py ROOT [links] [length] [dates] [paths] | check_docs.py --self-test
"""
import os
import re
import sys
import tempfile

MAX_LINES = 500
SESSION = re.compile(
    r"\b(first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|twelfth|"
    r"this|that|earlier|last|latest|previous|next|same|each|one|every)\s+sessions?\b|\bsessions'",
    re.IGNORECASE)
LINK = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
FENCE = re.compile(r"^\s*(```|~~~)")


def pages(root):
    found = []
    for name in ("README.md", "CHANGELOG.md"):
        if os.path.isfile(os.path.join(root, name)):
            found.append(os.path.join(root, name))
    for folder, _, files in os.walk(os.path.join(root, "docs")):
        found += [os.path.join(folder, f) for f in files if f.endswith(".md")]
    return sorted(found)


def prose_lines(path):
    """(line number, text) of the lines outside fenced code blocks."""
    inside = False
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if FENCE.match(line):
                inside = not inside
                continue
            if not inside:
                yield number, line


def slug(heading):
    text = re.sub(r"<[^>]+>", "", heading.strip().lower())
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)  # a link in a heading keeps its text
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path):
    seen = {}
    result = set()
    for _, line in prose_lines(path):
        match = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not match:
            continue
        base = slug(match.group(1))
        count = seen.get(base, 0)
        seen[base] = count + 1
        result.add(base if count == 0 else f"{base}-{count}")
    return result


def check_links(root):
    problems = []
    cache = {}
    for page in pages(root):
        for number, line in prose_lines(page):
            for target in LINK.findall(re.sub(r"`[^`]*`", "", line)):
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                path, _, anchor = target.partition("#")
                resolved = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
                where = f"{os.path.relpath(page, root)}:{number}"
                if not os.path.exists(resolved):
                    problems.append(f"{where}: the link '{target}' points to a file that does not exist")
                    continue
                if anchor and resolved.endswith(".md"):
                    if resolved not in cache:
                        cache[resolved] = anchors(resolved)
                    if anchor not in cache[resolved]:
                        problems.append(f"{where}: the link '{target}' names a heading that "
                                        f"{os.path.relpath(resolved, root)} does not have")
    return problems


def check_length(root):
    problems = []
    for page in pages(root):
        if os.path.basename(page) == "CHANGELOG.md":
            continue
        with open(page, encoding="utf-8") as f:
            count = sum(1 for _ in f)
        if count > MAX_LINES:
            problems.append(f"{os.path.relpath(page, root)}: {count} lines, more than {MAX_LINES}")
    return problems


def check_dates(root):
    problems = []
    for page in pages(root):
        with open(page, encoding="utf-8") as f:
            text = f.read()
        for match in SESSION.finditer(text):  # also across a line break
            number = text.count("\n", 0, match.start()) + 1
            phrase = " ".join(match.group(0).split())
            problems.append(f"{os.path.relpath(page, root)}:{number}: a fact dated by a "
                            f"session ('{phrase}'); give the date or the commit")
    return problems


PATH = re.compile(r"`((?:include|src|scripts|tests|data|docs|examples|apps|python|benchmarks|cmake)/"
                  r"[^`\s*{}<>]+)`")


def check_paths(root):
    problems = []
    for page in pages(root):
        if os.sep + "notes" + os.sep in page or os.path.basename(page) == "CHANGELOG.md":
            continue
        for number, line in prose_lines(page):
            for path in PATH.findall(line):
                path = path.rstrip(".,;:)")
                if not os.path.exists(os.path.join(root, path)):
                    problems.append(f"{os.path.relpath(page, root)}:{number}: '{path}' does not exist")
    return problems


CHECKS = {"links": check_links, "length": check_length, "dates": check_dates, "paths": check_paths}


def self_test():
    faults = {
        "links": {"README.md": "[a](docs/a.md#there)\n", "docs/a.md": "# Here\n"},
        "length": {"docs/a.md": "line\n" * (MAX_LINES + 1)},
        "dates": {"docs/a.md": "Measured in the ninth\nsession.\n"},
        "paths": {"docs/a.md": "See `include/s2kf/gone.hpp`.\n"},
    }
    clean = {"README.md": "[a](docs/a.md#here-and-there) [b](docs/b.md) ![c](docs/)\n",
             "docs/a.md": "# Here and there\n```cpp\n#include <x>\n[x](missing.md)\n```\n",
             "docs/b.md": "[back](../README.md) [self](#b) `docs/a.md`\n# B\n",
             "docs/notes/n.md": "Then in `include/s2kf/gone.hpp`.\n"}
    failures = []
    for name, check in CHECKS.items():
        for files, expect in ((faults[name], True), (clean, False)):
            with tempfile.TemporaryDirectory() as root:
                for rel, text in files.items():
                    os.makedirs(os.path.dirname(os.path.join(root, rel)), exist_ok=True)
                    with open(os.path.join(root, rel), "w", encoding="utf-8") as f:
                        f.write(text)
                found = bool(check(root))
                if found != expect:
                    failures.append(f"{name}: {'missed a fault' if expect else 'flagged a clean tree'}")
    for failure in failures:
        print(failure)
    return 1 if failures else 0


def main(argv):
    if argv[1:] == ["--self-test"]:
        return self_test()
    if len(argv) < 2 or not os.path.isdir(argv[1]):
        print("usage: check_docs.py ROOT [links] [length] [dates] [paths] | check_docs.py --self-test")
        return 2
    names = argv[2:] or list(CHECKS)
    unknown = [n for n in names if n not in CHECKS]
    if unknown:
        print(f"unknown check '{unknown[0]}' (use links, length, dates or paths)")
        return 2
    problems = [p for n in names for p in CHECKS[n](argv[1])]
    for problem in problems:
        print(problem)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

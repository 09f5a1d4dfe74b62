#!/usr/bin/python3
"""Checks the relative links of the project's Markdown files: each file exists, each #anchor is
a heading of the file it points into (GitHub's heading ids).

    toolchain/check_doc_links.py [ROOT]     (ctest: doc_links)

ROOT (default: the repository this script is in) is searched for *.md outside build*/ and
hidden directories. Links to http(s), mailto and the like are not followed; links inside code
(fenced blocks and `spans`) are not links. Prints one line per broken link (file:line: target:
why) and exits 1 if there is any, 0 otherwise. Standard library only.
"""
import os
import re
import sys
import unicodedata

# A link's or an image's target: "](target)" (the text before it may have begun lines above).
TARGET = re.compile(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
FENCE = re.compile(r"^\s*(```|~~~)")
CODE_SPAN = re.compile(r"`+[^`]*`+")


def slug(heading):
    """GitHub's id for a heading's text: markup dropped, lower case, every character but letters,
    digits, '_', '-' and spaces dropped, spaces made '-'."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link's text stays
    text = text.replace("`", "").lower()
    kept = []
    for ch in text:
        category = unicodedata.category(ch)
        if ch in "_- " or category[0] in "LMN":
            kept.append(ch)
    return "".join(kept).replace(" ", "-")


def prose_lines(path):
    """(line number, text) of a Markdown file's lines outside fenced code blocks."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    fenced = False
    for number, line in enumerate(lines, 1):
        if FENCE.match(line):
            fenced = not fenced
            continue
        if not fenced:
            yield number, line


def anchors(path):
    """Every heading id of a Markdown file (a repeated heading's ids get -1, -2, ... as GitHub
    gives them)."""
    seen = {}
    out = set()
    for _, line in prose_lines(path):
        m = HEADING.match(line)
        if not m:
            continue
        base = slug(m.group(2))
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def markdown_files(root):
    for directory, subdirs, files in os.walk(root):
        subdirs[:] = sorted(d for d in subdirs if not d.startswith(".") and
                            not d.startswith("build"))
        for name in sorted(files):
            if name.endswith(".md"):
                yield os.path.join(directory, name)


def broken_links(root):
    """(file, line, target, why) for every relative link that does not resolve."""
    cache = {}
    out = []
    for path in markdown_files(root):
        for number, line in prose_lines(path):
            prose = CODE_SPAN.sub("", line)
            for m in TARGET.finditer(prose):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target, re.I):
                    continue  # http:, https:, mailto: ...
                file_part, _, anchor = target.partition("#")
                dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) \
                    if file_part else path
                if not os.path.exists(dest):
                    out.append((path, number, target, "no such file"))
                    continue
                if not anchor or not dest.endswith(".md"):
                    continue
                if dest not in cache:
                    cache[dest] = anchors(dest)
                if anchor not in cache[dest]:
                    out.append((path, number, target, "no such heading"))
    return out


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..")
    root = os.path.abspath(root)
    broken = broken_links(root)
    for path, number, target, why in broken:
        print(f"{os.path.relpath(path, root)}:{number}: {target}: {why}")
    if broken:
        print(f"{len(broken)} broken link(s)")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Copies a `docs/bench/NAME.md` write-up into BENCHMARKS.md.

BENCHMARKS.md holds each write-up under a marker line
`<!-- from docs/bench/NAME.md -->`, with its headings shifted so that the
first is a `###` (`#` → `###`, `##` → `####` for most; lines inside fenced
code blocks are left alone).
The section runs to the next such marker or `## ` heading.

    python3 scripts/bench_sync.py NAME [NAME ...]            # replace existing sections
    python3 scripts/bench_sync.py NAME --before OTHER        # insert a new one before OTHER's

Run from the repository root. Standard library only.
"""

import argparse
import os
import re
import sys

MARKER = "<!-- from docs/bench/{}.md -->"


def shifted(name):
    """The write-up's lines, headings shifted two levels, under its marker."""
    try:
        with open(f"docs/bench/{name}.md") as f:
            doc = f.read().rstrip("\n").split("\n")
    except OSError as e:
        sys.exit(f"docs/bench/{name}.md: {e.strerror}")
    # The first heading becomes `###` (most write-ups start at `#`, some
    # already at `###`), the others keep their depth below it.
    first = next((len(m.group(1)) for l in doc if (m := re.match(r"^(#+) ", l))), 3)
    shift = "#" * max(0, 3 - first)
    out, fence = [MARKER.format(name)], False
    for line in doc:
        if line.startswith("```"):
            fence = not fence
        if not fence and re.match(r"^#{1,4} ", line):
            line = shift + line
        out.append(line)
    return out + [""]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="+")
    ap.add_argument("--before", help="insert new sections before this write-up's section")
    ap.add_argument("--file", default="BENCHMARKS.md")
    a = ap.parse_args()
    with open(a.file) as f:
        lines = f.read().split("\n")
    for name in a.names:
        section = shifted(name)
        marker = MARKER.format(name)
        if marker in lines:
            i = lines.index(marker)
            j = i + 1
            while j < len(lines) and not (
                lines[j].startswith("<!-- from docs/bench/") or lines[j].startswith("## ")
            ):
                j += 1
            lines[i:j] = section
        elif a.before:
            anchor = MARKER.format(a.before)
            if anchor not in lines:
                sys.exit(f"{a.file}: no section from docs/bench/{a.before}.md")
            i = lines.index(anchor)
            lines[i:i] = section
        else:
            sys.exit(f"{a.file}: no section from docs/bench/{name}.md (use --before)")
    with open(a.file + ".tmp", "w") as f:
        f.write("\n".join(lines))
    os.replace(a.file + ".tmp", a.file)


if __name__ == "__main__":
    main()

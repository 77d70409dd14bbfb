#!/usr/bin/env python3
"""Check that every relative link of Markdown files points to an existing file (and heading).

  tools/docs/check_links.py [--root DIR] PATH...

PATH is a Markdown file or a folder (its *.md files, recursively). For each link `[text](target)`,
image `![alt](target)` or reference `[name]: target` outside code, a relative target must name an
existing file or folder (relative to the linking file); `#anchor` (alone or after a .md file) must
be a heading of that file, slugged as GitHub does. External links (http:, https:, mailto:) are not
followed. Prints every broken link as FILE:LINE: and exits 1 if there is one.
"""

import argparse
import os
import re
import sys
import urllib.parse

LINK = re.compile(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$")
EXTERNAL = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def strip_code(lines):
    """The lines with fenced blocks blanked and inline code spans removed (line numbers kept)."""
    out = []
    fence = None
    for line in lines:
        m = re.match(r"^\s*(```+|~~~+)", line)
        if fence:
            if m and m.group(1)[0] == fence[0] and len(m.group(1)) >= len(fence):
                fence = None
            out.append("")
            continue
        if m:
            fence = m.group(1)
            out.append("")
            continue
        out.append(re.sub(r"(`+)(?:(?!\1).)+?\1", "", line))
    return out


def slug(heading):
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links: their text
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(path, cache):
    if path not in cache:
        found = set()
        counts = {}
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        in_fence = None
        for line in lines:
            m = re.match(r"^\s*(```+|~~~+)", line)
            if m:
                in_fence = None if in_fence else m.group(1)
                continue
            if in_fence:
                continue
            h = re.match(r"^\s{0,3}#{1,6}\s+(.*?)\s*#*\s*$", line)
            if h:
                s = slug(h.group(1))
                n = counts.get(s, 0)
                counts[s] = n + 1
                found.add(s if n == 0 else f"{s}-{n}")
            for a in re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", line):
                found.add(a)
        cache[path] = found
    return cache[path]


def markdown_files(paths):
    for p in paths:
        if os.path.isdir(p):
            for d, _, files in sorted(os.walk(p)):
                for f in sorted(files):
                    if f.endswith(".md"):
                        yield os.path.join(d, f)
        else:
            yield p


def check(path, root, cache):
    problems = []
    with open(path, encoding="utf-8") as f:
        lines = strip_code(f.read().split("\n"))
    shown = os.path.relpath(path, root)
    for n, line in enumerate(lines, 1):
        targets = LINK.findall(line)
        m = REFERENCE.match(line)
        if m:
            targets.append(m.group(1))
        for target in targets:
            if EXTERNAL.match(target):
                continue
            file_part, _, anchor = target.partition("#")
            file_part = urllib.parse.unquote(file_part)
            dest = os.path.normpath(os.path.join(os.path.dirname(path), file_part)) if file_part else path
            if not os.path.exists(dest):
                problems.append(f"{shown}:{n}: link to {target}: no such file {os.path.relpath(dest, root)}")
                continue
            if anchor and dest.endswith(".md") and os.path.isfile(dest):
                if urllib.parse.unquote(anchor) not in anchors(dest, cache):
                    problems.append(f"{shown}:{n}: link to {target}: no heading '#{anchor}' in "
                                    f"{os.path.relpath(dest, root)}")
    return problems


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    ap.add_argument("paths", nargs="+", help="Markdown files or folders, relative to --root")
    ap.add_argument("--root", default=os.path.normpath(os.path.join(here, "..", "..")),
                    help="the source tree (default: this script's)")
    a = ap.parse_args(argv)
    cache = {}
    problems = []
    files = 0
    for p in a.paths:
        full = os.path.join(a.root, p)
        if not os.path.exists(full):
            print(f"check_links: error: {p}: no such file or folder", file=sys.stderr)
            return 2
        for f in markdown_files([full]):
            files += 1
            problems += check(f, a.root, cache)
    for p in problems:
        print(p)
    print(f"check_links: {files} files, {len(problems)} broken links", file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

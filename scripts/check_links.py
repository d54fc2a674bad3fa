#!/usr/bin/env python3
"""Relative links and images in the user-facing Markdown files point at something.

The README is a guide that sends readers to docs/, and the docs link to each other's
sections; a page renamed or a heading reworded would otherwise leave a dead link that
nobody notices until a reader follows it. For every `[text](target)`, `![alt](target)`
and reference definition `[id]: target` outside code, a relative target must name a file
or folder that exists, and a `#fragment` must be the anchor of a heading in the target
Markdown file (or in the same file when the target is only `#fragment`). Anchors follow
GitHub's rules: the heading's text without its Markdown, lowercased, every character
that is not a letter, digit, space, '-' or '_' removed, spaces turned into '-', and a
repeated anchor suffixed -1, -2, ... Absolute URLs (http:, mailto:, ...) are not checked:
that needs the network, and the test suite runs without one.

Usage: check_links.py [SOURCE_DIR]   prints FILE:LINE: target: why for each broken link;
exit 1 when there is any, 0 otherwise.
"""
import pathlib
import re
import sys
import urllib.parse

ROOT = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".").resolve()
CHECKED = ["README.md", "docs/*.md", "scenes/README.md", "tests/fuzz/README.md", "CHANGELOG.md"]

FENCE = re.compile(r"^\s{0,3}(```|~~~)")
CODE_SPAN = re.compile(r"(`+)(.+?)\1")
INLINE = re.compile(r"\]\(\s*(<[^>]*>|[^)\s]*)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*(<[^>]*>|\S+)")
HEADING = re.compile(r"^\s{0,3}(#{1,6})\s+(.*?)\s*#*\s*$")
SCHEME = re.compile(r"^[a-zA-Z][a-zA-Z0-9+.-]*:")


def prose_lines(text):
    """(line number, line) outside fenced code blocks, with code spans blanked out."""
    fence = None
    for number, line in enumerate(text.split("\n"), 1):
        match = FENCE.match(line)
        if match:
            if fence is None:
                fence = match.group(1)
            elif match.group(1) == fence:
                fence = None
            continue
        if fence is None:
            yield number, CODE_SPAN.sub(lambda m: " " * len(m.group(0)), line)


def anchor(heading):
    """GitHub's anchor for a heading's text."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links and images: their text
    text = re.sub(r"<[^>]+>", "", text)  # inline HTML
    text = text.replace("`", "")
    text = re.sub(r"(\*\*|__|\*|_(?=\W)|(?<=\W)_)", "", text)  # emphasis markers
    text = text.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)  # \w keeps letters and digits of any script, and _
    return text.replace(" ", "-")


_anchors = {}


def anchors_of(path):
    if path not in _anchors:
        seen = {}
        found = set()
        fence = None
        for line in path.read_text(encoding="utf-8").split("\n"):
            match = FENCE.match(line)
            if match:
                if fence is None:
                    fence = match.group(1)
                elif match.group(1) == fence:
                    fence = None
                continue
            heading = HEADING.match(line) if fence is None else None
            if heading:
                base = anchor(heading.group(2))
                count = seen.get(base, 0)
                seen[base] = count + 1
                found.add(base if count == 0 else f"{base}-{count}")
        _anchors[path] = found
    return _anchors[path]


def check(source, target):
    """Why the link `target` in `source` is broken, or None."""
    if target.startswith("<") and target.endswith(">"):
        target = target[1:-1]
    if not target or SCHEME.match(target) or target.startswith("//"):
        return None
    path_part, _, fragment = target.partition("#")
    path_part = urllib.parse.unquote(path_part)
    if path_part.startswith("/"):
        resolved = ROOT / path_part.lstrip("/")
    elif path_part:
        resolved = (source.parent / path_part).resolve()
    else:
        resolved = source
    if not resolved.exists():
        return "no such file"
    if ROOT not in resolved.parents and resolved != ROOT:
        return "outside the repository"
    if fragment:
        if resolved.is_dir() or resolved.suffix.lower() != ".md":
            return None  # anchors into code or data files are line numbers GitHub makes up
        if urllib.parse.unquote(fragment).lower() not in anchors_of(resolved):
            return f"no heading with the anchor #{fragment} in {resolved.relative_to(ROOT)}"
    return None


def main():
    files = sorted({p for pattern in CHECKED for p in ROOT.glob(pattern)})
    broken = 0
    links = 0
    for source in files:
        for number, line in prose_lines(source.read_text(encoding="utf-8")):
            targets = [m.group(1) for m in INLINE.finditer(line)]
            reference = REFERENCE.match(line)
            if reference:
                targets.append(reference.group(1))
            for target in targets:
                links += 1
                why = check(source, target)
                if why:
                    broken += 1
                    print(f"{source.relative_to(ROOT)}:{number}: {target}: {why}")
    print(f"check_links: {links} links in {len(files)} files, {broken} broken")
    return 1 if broken else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Check the documentation's cross-references (run from anywhere; exit 1 on a failure).

1. Every relative Markdown link `[text](target)` in README.md, examples/field/README.md
   and docs/*.md resolves to a file of the repository, and every `#anchor` (in the same
   page or another) to a heading of that page (GitHub's anchor rule).
2. Every mention `docs/PAGE.md "Heading"` (or `PAGE.md "Heading"`, also wrapped over
   comment lines) in those pages and in the sources (host, shared, firmware, tests,
   scripts) names a page that exists, and a heading of it that starts with the quoted
   text (case and backticks ignored). A quote that is no heading of the page (a bold
   paragraph's title, a table's row) is listed as a warning, not a failure.
3. Every bare path `docs/PAGE.md` in those files names a page that exists.

Usage: python3 scripts/check-doc-links.py [--quiet]
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", ROOT / "examples/field/README.md"] + sorted((ROOT / "docs").glob("*.md"))
SOURCES = ["host", "shared", "firmware", "tests", "scripts"]
SOURCE_EXT = {".rs", ".py", ".sh", ".toml"}


def strip_code_blocks(text):
    """The text with fenced code blocks blanked (links in them are not links)."""
    out, fenced = [], False
    for line in text.split("\n"):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            out.append("")
        else:
            out.append("" if fenced else line)
    return "\n".join(out)


def anchors(page):
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces to '-'."""
    seen, result = {}, set()
    for line in strip_code_blocks(page.read_text()).split("\n"):
        m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        a = re.sub(r"[^\w\- ]", "", m.group(1).lower()).replace(" ", "-")
        n = seen.get(a, 0)
        seen[a] = n + 1
        result.add(a if n == 0 else f"{a}-{n}")
    return result


def headings(page):
    """A page's heading texts, lower case, backticks dropped."""
    text = strip_code_blocks(page.read_text())
    return [m.group(1).replace("`", "").lower().strip()
            for m in re.finditer(r"^#{1,6}\s+(.*)$", text, re.M)]


def check_links(failures):
    for page in PAGES:
        if not page.is_file():
            continue
        text = strip_code_blocks(page.read_text())
        for m in re.finditer(r"\]\(([^)\s]+)\)", text):
            target = m.group(1)
            if target.startswith(("http://", "https://", "mailto:")):
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            where = f"{page.relative_to(ROOT)}: ({target})"
            if not dest.exists():
                failures.append(f"{where}: no file {path}")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                failures.append(f"{where}: no heading #{anchor} in {path or page.name}")


MENTION = re.compile(r"((?:docs/)?[\w.-]+\.md)\)?,?\s+\"([^\"]{3,120})\"")


# A bare path of a page in docs/ (`docs/trust.md`), wherever it is written.
BARE = re.compile(r"(?<![\w/.-])(docs/[\w.-]+\.md)")


def mentions(text):
    """(page, quote) pairs of `PAGE.md "Heading"` mentions, comment prefixes joined."""
    joined = re.sub(r"\n\s*(?://[/!]?|#)?\s*", " ", text)
    return MENTION.findall(joined)


def check_mentions(failures, warnings):
    files = [p for p in PAGES if p.is_file()]
    for d in SOURCES:
        files += [p for p in (ROOT / d).rglob("*") if p.suffix in SOURCE_EXT and p.is_file()]
    for f in files:
        if "target" in f.relative_to(ROOT).parts or f.resolve() == pathlib.Path(__file__).resolve():
            continue
        try:
            text = f.read_text()
        except UnicodeDecodeError:
            continue
        for path in set(BARE.findall(text)):
            if not (ROOT / path).is_file():
                failures.append(f"{f.relative_to(ROOT)}: {path}: no such page")
        for name, quote in mentions(text):
            name = name.removeprefix("docs/")
            page = ROOT / "docs" / name if name != "README.md" else ROOT / "README.md"
            if name == "README.md" and f.parent.name != "docs":
                continue
            where = f"{f.relative_to(ROOT)}: {name} \"{quote}\""
            if not page.is_file():
                if name != "README.md":
                    failures.append(f"{where}: no page docs/{name}")
                continue
            q = quote.replace("`", "").lower().strip()
            if not any(h.startswith(q) for h in headings(page)):
                warnings.append(f"{where}: no heading starting so")


def main():
    failures, warnings = [], []
    check_links(failures)
    check_mentions(failures, warnings)
    if "--quiet" not in sys.argv:
        for w in warnings:
            print("warning:", w)
    for f in failures:
        print("FAIL:", f)
    print(f"{len(failures)} failures, {len(warnings)} warnings")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())

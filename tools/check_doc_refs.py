#!/usr/bin/env python3
"""Checks that the README's and docs/' links and file references resolve.

Usage: tools/check_doc_refs.py [FILE.md ...]   (default: README.md, docs/*.md,
tools/bench/HISTORY.md). Exits 1 and lists what does not resolve:
  - a Markdown link [text](target) to a file (relative to the document) or an anchor;
  - a link followed by a quoted section, [x](doc.md), "Section": a heading of doc.md
    must contain the quoted text;
  - a path in backquotes (`src/...`, `data/...`, `name.hpp`): relative to the
    repository's root, or, without a folder, a file of that name anywhere in it;
  - "Section" in [x](doc.md): likewise;
  - in the code's comments (without arguments): docs/x.md, "Section".
Build outputs (build/...) and placeholders (<case>, FILE) are skipped.
"""
import pathlib
import re
import subprocess
import sys

root = pathlib.Path(__file__).resolve().parent.parent
tracked = subprocess.run(["git", "-C", str(root), "ls-files"], capture_output=True, text=True,
                         check=True).stdout.split()
basenames = {pathlib.PurePath(p).name for p in tracked}
top_dirs = {"src", "include", "tools", "data", "docs", "tests", ".ci"}
extensions = (".md", ".hpp", ".cpp", ".h", ".sh", ".py", ".ini", ".txt", ".png", ".svg")


def expand_braces(text):
    """`a{1,2}b` -> [a1b, a2b]."""
    m = re.search(r"\{([^{}]*)\}", text)
    if not m:
        return [text]
    return [e for alt in m.group(1).split(",") for e in expand_braces(text[:m.start()] + alt + text[m.end():])]


def headings(path):
    return [line.lstrip("#").strip() for line in path.read_text().splitlines() if line.startswith("#")]


def anchor(heading):
    return re.sub(r"[^\w\- ]", "", heading.lower()).replace(" ", "-")


def check(doc):
    problems = []
    text = doc.read_text()
    text_no_code = re.sub(r"```.*?```", "", text, flags=re.S)
    for m in re.finditer(r"\[[^\]]*\]\(([^)\s]+)\)", text_no_code):
        target = m.group(1)
        if re.match(r"[a-z]+:", target):
            continue
        path_part, _, frag = target.partition("#")
        dest = (doc.parent / path_part).resolve() if path_part else doc
        if not dest.exists():
            problems.append(f"link to {target}: no such file")
            continue
        if frag and dest.suffix == ".md" and frag not in {anchor(h) for h in headings(dest)}:
            problems.append(f"link to {target}: no such heading")
        quoted = re.match(r'\)?,?\s+"([^"]+)"', text_no_code[m.end():])
        if quoted and dest.suffix == ".md":
            section = " ".join(quoted.group(1).split())
            if not any(section in h for h in headings(dest)):
                problems.append(f'section "{section}" of {path_part}: no such heading')
    for m in re.finditer(r'"([^"]+)" in\s+\[[^\]]*\]\(([^)#\s]+\.md)\)', text_no_code):
        section, dest = " ".join(m.group(1).split()), (doc.parent / m.group(2)).resolve()
        if dest.exists() and not any(section in h for h in headings(dest)):
            problems.append(f'section "{section}" of {m.group(2)}: no such heading')
    for m in re.finditer(r"`([^`\s]+)`", text_no_code):
        token = m.group(1).rstrip(".,;:")
        if "<" in token or token.startswith(("build/", "-", "$")) or re.search(r"[A-Z]{3,}", token):
            continue
        first = token.split("/")[0]
        is_path = ("/" in token and first in top_dirs) or ("/" not in token and token.endswith(extensions))
        if not is_path:
            continue
        for name in expand_braces(token):
            if "/" in name:
                if not (root / name).exists():
                    problems.append(f"`{name}`: no such file or folder")
            elif name not in basenames:
                problems.append(f"`{name}`: no file of that name in the repository")
    return problems


def check_source(path):
    """A comment's reference to a document, `docs/x.md, "Section"`, in the code."""
    problems = []
    text = re.sub(r"\n\s*(//+|#)\s*", " ", path.read_text(errors="replace"))
    for m in re.finditer(r'((?:docs/[\w-]+|tools/bench/HISTORY|README)\.md)(?:,\s*"([^"]+)")?', text):
        dest = root / m.group(1)
        if not dest.exists():
            problems.append(f"{m.group(1)}: no such file")
        elif m.group(2) and not any(" ".join(m.group(2).split()) in h for h in headings(dest)):
            problems.append(f'section "{m.group(2)}" of {m.group(1)}: no such heading')
    return problems


docs = [pathlib.Path(a).resolve() for a in sys.argv[1:]] or \
    [root / "README.md", *sorted((root / "docs").glob("*.md")), root / "tools/bench/HISTORY.md"]
sources = [] if sys.argv[1:] else \
    [root / p for p in tracked if p.endswith((".hpp", ".cpp", ".sh", ".py", ".ini", "CMakeLists.txt"))
     and p != "tools/check_doc_refs.py"]
failed = False
for path, problems in [(d, check(d)) for d in docs] + [(s, check_source(s)) for s in sources]:
    for problem in problems:
        print(f"{path.relative_to(root)}: {problem}")
        failed = True
sys.exit(1 if failed else 0)

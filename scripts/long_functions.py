#!/usr/bin/env python3
"""Lists C++ functions longer than a limit, longest first, and source files (.cpp) longer than
another; exits 1 when any is (CI runs it).

    scripts/long_functions.py [--limit 80] [--file-limit 600] [--root .] [--all]

A function is a brace block opened at namespace or class level after a parameter list (with its
qualifiers, trailing return type or constructor initialisers); its length runs from the line of
its name to its closing brace. Lambdas count towards the function that holds them. Comments and
string literals are blanked first. Generated code (build*/) and tests (tests/) are not counted,
as issue 17 asks.
"""
import argparse
import pathlib
import re
import sys

SOURCE_SUFFIXES = {".cpp", ".hpp", ".h", ".cc"}
SKIPPED_FOLDERS = {"build", "tests", "node_modules", ".git"}
CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else|try)\s*(\(|$)")
AFTER_PARAMETERS = re.compile(r"\)\s*(const|noexcept(\([^)]*\))?|override|final|mutable|&&?|->[^{;]*|\s)*$")
INITIALISERS = re.compile(r"\)\s*(noexcept\s*)?:\s*[\w:<>]+\s*[({]")
SCOPE = re.compile(r"\b(namespace|class|struct|union|enum)\b[^()]*$|extern\s+\"C\"\s*$")


def blank_comments_and_strings(text: str) -> str:
    """The text with comments, string and character literals replaced by spaces (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        two = text[i:i + 2]
        if two == "//":
            j = text.find("\n", i)
            j = n if j < 0 else j
        elif two == "/*":
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif text[i] == "R" and text[i + 1:i + 2] == '"':
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append("R")
            i += 1
        elif text[i] in "\"'":
            quote, j = text[i], i + 1
            while j < n and text[j] != quote and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j += 1
        else:
            out.append(text[i])
            i += 1
            continue
        out.append("".join(c if c == "\n" else " " for c in text[i:j]))
        i = j
    return "".join(out)


def functions(text: str):
    """(name, first line, last line) of every function body in the text."""
    code = blank_comments_and_strings(text)
    stack = []  # kinds of the open braces: scope, function, other, init
    header_start = 0
    found = []
    for pos, c in enumerate(code):
        if c in ";":
            if not stack or stack[-1] == "scope":
                header_start = pos + 1
        elif c == "{":
            header = code[header_start:pos]
            at_scope = all(k == "scope" for k in stack)
            if not at_scope:
                stack.append("other")
            elif INITIALISERS.search(header) and re.search(r"[\w>]\s*$", header):
                stack.append("init")  # a member's brace initialiser before the body
            elif SCOPE.search(header.strip()) or "=" in header.split(")")[-1]:
                stack.append("scope" if SCOPE.search(header.strip()) else "other")
                header_start = pos + 1
            elif AFTER_PARAMETERS.search(header) or INITIALISERS.search(header):
                if CONTROL.search(header.strip()):
                    stack.append("other")
                else:
                    name = re.search(r"([~\w:<>=!+\-*/\[\]]+)\s*\(", header)
                    first = code.count("\n", 0, header_start + len(header) - len(header.lstrip())) + 1
                    stack.append(("function", name.group(1) if name else "?", first))
            else:
                stack.append("other")
        elif c == "}":
            if not stack:
                continue
            kind = stack.pop()
            if isinstance(kind, tuple):
                found.append((kind[1], kind[2], code.count("\n", 0, pos) + 1))
            if kind != "init" and all(k == "scope" for k in stack):
                header_start = pos + 1
    return found


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--limit", type=int, default=80, help="longest allowed function, in lines")
    p.add_argument("--file-limit", type=int, default=600, help="longest allowed .cpp file, in lines")
    p.add_argument("--root", default=str(pathlib.Path(__file__).resolve().parent.parent))
    p.add_argument("--all", action="store_true", help="list every function over 60 lines, not only those over the limit")
    a = p.parse_args()
    root = pathlib.Path(a.root)
    rows, long_files = [], []
    for path in sorted(root.rglob("*")):
        rel = path.relative_to(root)
        if path.suffix not in SOURCE_SUFFIXES or any(part in SKIPPED_FOLDERS or part.startswith("build") for part in rel.parts):
            continue
        text = path.read_text(errors="replace")
        for name, first, last in functions(text):
            rows.append((last - first + 1, f"{rel}:{first}", name))
        lines = text.count("\n")
        if path.suffix == ".cpp" and lines > a.file_limit:
            long_files.append((lines, str(rel)))
    rows.sort(reverse=True)
    shown = [r for r in rows if r[0] > (60 if a.all else a.limit)]
    for length, where, name in shown:
        print(f"{length:5d}  {where}  {name}", flush=True)
    for lines, rel in sorted(long_files, reverse=True):
        print(f"{lines:5d}  {rel}  (file)", flush=True)
    over = sum(1 for r in rows if r[0] > a.limit)
    print(f"{len(rows)} functions; {over} over {a.limit} lines; {len(long_files)} .cpp files over {a.file_limit} lines",
          file=sys.stderr)
    return 1 if over or long_files else 0


if __name__ == "__main__":
    sys.exit(main())

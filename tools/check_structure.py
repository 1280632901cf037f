#!/usr/bin/env python3
"""The house rules that a reviewer would otherwise count by hand (issue 35's bar).

  - no kernel header (include/tridex/, detail/ included) above 700 lines;
  - no function above 120 lines in include/, gcode/ and tools/ (from the first line of its
    declaration to its closing brace, comments and blank lines included, lambdas counted in the
    function that holds them);
  - README.md at most 250 lines;
  - no std::thread (or jthread, async) outside include/tridex/parallel.hpp and the tests: one pool;
  - the bundled machines' names spelled out in one source file only;
  - no TEST_CASE in a test header (CTest runs each suite file by file).

Usage: tools/check_structure.py [ROOT]   exit 0 when every rule holds, 1 with one line a breach.
The function finder is a brace matcher over the source with comments, strings and preprocessor
lines blanked out: it needs no compiler and errs toward counting more, never less.
"""
import pathlib
import re
import sys

MAX_HEADER_LINES = 700
MAX_FUNCTION_LINES = 120
MAX_README_LINES = 250
SOURCE_DIRS = ("include", "gcode", "tools")
SUFFIXES = {".hpp", ".cpp", ".h", ".cc"}
BUNDLED_MACHINES = ("ac-trunnion", "bc-trunnion", "xyzac-trt", "xyzbc-trt", "xyzab-tdr", "b-head-c-table", "head-head", "hmc-b-table")


def blank_out(text, keep_strings=False):
    """The source with comments, string and character literals and preprocessor lines replaced
    by spaces (newlines kept), so that braces and parentheses in them do not count; with
    keep_strings, only the comments go."""
    out = list(text)
    i, n = 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c == "#":
            while i < n and text[i] != "\n":  # a directive, with its continuation lines
                if text[i] == "\\" and i + 1 < n and text[i + 1] == "\n":
                    out[i] = " "
                    i += 2
                    continue
                out[i] = " "
                i += 1
            continue
        if c == "\n":
            line_start = True
            i += 1
            continue
        if not c.isspace():
            line_start = False
        if text.startswith("//", i):
            while i < n and text[i] != "\n":
                out[i] = " "
                i += 1
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            end = n if end < 0 else end + 2
            for k in range(i, end):
                if text[k] != "\n":
                    out[k] = " "
            i = end
        elif not keep_strings and c == "R" and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            end = n if end < 0 else end + len(m.group(1)) + 2
            for k in range(i, end):
                if text[k] != "\n":
                    out[k] = " "
            i = end
        elif c in "\"'":
            if keep_strings or c == "'" and i > 0 and text[i - 1].isalnum():  # a digit separator: 1'000'000
                i += 1
                continue
            k = i + 1
            while k < n and text[k] != c and text[k] != "\n":
                k += 2 if text[k] == "\\" else 1
            for j in range(i, min(k + 1, n)):
                if text[j] != "\n":
                    out[j] = " "
            i = k + 1
        else:
            i += 1
    return "".join(out)


NON_FUNCTION = re.compile(r"\b(namespace|class|struct|union|enum)\b")
CONTROL = re.compile(r"\b(if|for|while|switch|catch|do|else|try)\s*$")


def functions(text):
    """(first line, last line, name) of each outermost function body in C++ source."""
    src = blank_out(text)
    found = []
    stack = []  # one entry per open brace: "scope" (namespace/class/extern), "function", "other"
    stmt_start = 0  # where the current statement at this scope began
    continued = None  # where the last outermost function began, while a `{` may still extend it
    i, n = 0, len(src)
    while i < n:
        c = src[i]
        if c in ";":
            if not any(k == "function" for k, _ in stack):
                stmt_start = i + 1
                continued = None
        elif c == "{":
            if any(k == "function" for k, _ in stack) or (stack and stack[-1][0] == "other"):
                stack.append(("other", i))
            else:
                stmt = src[stmt_start:i]
                stmt_nt = re.sub(r"template\s*<[^{};]*?>\s*", "", stmt).strip()
                kind = "other"
                if re.search(r"\bextern\s*$", stmt_nt) or NON_FUNCTION.search(stmt_nt.split("(")[0]) and ")" not in stmt_nt.split("{")[0][-2:]:
                    kind = "scope"
                    if re.match(r"\s*(enum)\b", stmt_nt) or re.search(r"=\s*$", stmt_nt):
                        kind = "other"
                elif "(" in stmt_nt and not re.search(r"=\s*$", stmt_nt) and not CONTROL.search(stmt_nt.split("(")[0]):
                    kind = "function"
                start = stmt_start
                if kind == "other" and continued is not None and re.fullmatch(r"[\s,]*(\w+\s*)?", stmt_nt):
                    # a constructor's body after a brace-initialised member: `: a_{x} {`
                    kind, start = "function", continued
                stack.append((kind, start))
                continued = None
            if stack[-1][0] == "scope":
                stmt_start = i + 1
        elif c == "}":
            if stack:
                kind, start = stack.pop()
                if kind == "function" and not any(k == "function" for k, _ in stack):
                    continued = start  # until the next `;`: a constructor's initialiser list may go on
                if kind == "function":
                    first = src.count("\n", 0, start) + 1
                    # the declaration starts at its first non-blank character
                    while first <= src.count("\n", 0, i) and not src.splitlines()[first - 1].strip():
                        first += 1
                    last = src.count("\n", 0, i) + 1
                    sig = src[start:src.find("(", start)].split()
                    found.append((first, last, sig[-1] if sig else "?"))
                if not any(k == "function" for k, _ in stack):
                    stmt_start = i + 1
        i += 1
    return found


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).resolve().parents[1])
    breaches = []
    for d in SOURCE_DIRS:
        for path in sorted((root / d).rglob("*")):
            if path.suffix not in SUFFIXES or not path.is_file():
                continue
            rel = path.relative_to(root)
            text = path.read_text(encoding="utf-8", errors="replace")
            lines = text.count("\n")
            if rel.parts[:2] == ("include", "tridex") and path.suffix == ".hpp" and lines > MAX_HEADER_LINES:
                breaches.append(f"{rel}: {lines} lines, a kernel header holds at most {MAX_HEADER_LINES}")
            for first, last, name in functions(text):
                if last - first + 1 > MAX_FUNCTION_LINES:
                    breaches.append(f"{rel}:{first}: {name} is {last - first + 1} lines, at most {MAX_FUNCTION_LINES}")
            if rel.as_posix() != "include/tridex/parallel.hpp" and re.search(
                    r"std::(thread|jthread|async)\b(?!::hardware_concurrency)", blank_out(text)):
                breaches.append(f"{rel}: starts threads of its own; use include/tridex/parallel.hpp")
    for header in sorted((root / "tests").rglob("*.hpp")):
        if "node_modules" not in header.parts and re.search(r"\bTEST_CASE\b", blank_out(header.read_text(encoding="utf-8", errors="replace"))):
            breaches.append(f"{header.relative_to(root)}: a TEST_CASE in a header, which CTest's per-file runs never reach")
    readme = root / "README.md"
    if readme.exists() and readme.read_text(encoding="utf-8").count("\n") > MAX_README_LINES:
        breaches.append(f"README.md: {readme.read_text(encoding='utf-8').count(chr(10))} lines, at most {MAX_README_LINES}")
    holders = set()
    for d in SOURCE_DIRS:
        for path in (root / d).rglob("*"):
            if path.suffix in SUFFIXES and path.is_file():
                src = blank_out(path.read_text(encoding="utf-8", errors="replace"), keep_strings=True)
                if any(f'"{m}"' in src for m in BUNDLED_MACHINES):
                    holders.add(path.relative_to(root).as_posix())
    if len(holders) > 1:
        breaches.append("the bundled machines' names are spelled out in " + ", ".join(sorted(holders)) + ": one registry only")
    for b in breaches:
        print(b)
    print(f"check_structure: {len(breaches)} breach{'es' if len(breaches) != 1 else ''}")
    return 1 if breaches else 0


if __name__ == "__main__":
    sys.exit(main())

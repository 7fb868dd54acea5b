#!/usr/bin/env python3
"""Reports C++ class/struct bodies and function bodies longer than given limits.

Usage: check_code_size.py [--class-limit N] [--function-limit M] [--exclude FILE ...] DIR...

Scans the .cpp and .hpp files under each DIR (recursively). A body's length is the number of lines
from the line of its opening brace to the line of its closing brace, both included. Exits 1 when any
body exceeds its limit (each is printed as path:line: kind name: lines > limit), 0 otherwise.

The parsing is a brace-matching heuristic, not a C++ parser:
  - comments, string and character literals (raw strings included) are blanked out first;
  - a brace whose preceding text (back to the previous ';', '{' or '}') starts a class, struct or
    union is a class body; `namespace` and `extern "C"` blocks and enums are neither;
  - a brace after a parameter list's ')' (optionally followed by const, noexcept, override, a
    trailing return type or a member initializer list) at namespace or class scope is a function
    body;
  - braces inside a function body (blocks, lambdas, initializer lists) belong to that function:
    a lambda counts as part of its enclosing function and is not reported on its own; a class
    defined inside a function counts only toward the function. A lambda stored in a variable at
    namespace scope (auto f = [] { ... };) is not a function body and is not reported.
--exclude takes file paths (as given under DIR, or just the file name) whose findings are printed
as excluded and do not fail the check.
"""
import argparse
import os
import re
import sys

CLASS_RE = re.compile(r"(?:^|[\s;{}])(?:template\s*<[^;{}]*>\s*)?(class|struct|union)\s+(?:\[\[[^\]]*\]\]\s*)?(?:alignas\s*\([^)]*\)\s*)?([A-Za-z_][\w:]*)?")
NAMESPACE_RE = re.compile(r"(?:^|[\s;{}])(namespace|extern\s+\"[^\"]*\")")  # literals are blanked first
ENUM_RE = re.compile(r"(?:^|[\s;{}])enum\b")
FUNC_NAME_RE = re.compile(r"([~A-Za-z_][\w:<>~]*(?:operator\s*[^\s(]+)?)\s*\($")


def strip_comments_and_strings(text):
    """Replaces comments and literals by spaces, keeping newlines (so line numbers stay)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "R" and i + 1 < n and text[i + 1] == '"' and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i + m.end())
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:end]))
                i = end
            else:
                out.append(c)
                i += 1
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum() and \
                    (i + 2 >= n or text[i + 2] != "'"):
                out.append(" ")
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * max(0, j - i - 2) + (c if j - i >= 2 else ""))
            i = j
        elif c == "#" and (i == 0 or text[text.rfind("\n", 0, i) + 1:i].strip() == ""):
            # Preprocessor line (with continuations): no braces of ours.
            j = i
            while True:
                k = text.find("\n", j)
                if k < 0:
                    k = n
                    break
                if text[k - 1] == "\\":
                    j = k + 1
                    continue
                break
            out.append(re.sub(r"[^\n]", " ", text[i:k]))
            i = k
        else:
            out.append(c)
            i += 1
    return "".join(out)


def classify(head):
    """What a '{' opens, from the text since the previous ';', '{' or '}'."""
    h = " ".join(head.split())
    if NAMESPACE_RE.search(" " + h) and not h.rstrip().endswith(")"):
        return "namespace", None
    if ENUM_RE.search(" " + h):
        return "other", None
    m = CLASS_RE.search(" " + h)
    if m and "(" not in h[:m.start()] and not h.rstrip().endswith(")"):
        return "class", m.group(2) or "(anonymous)"
    # Function: a parameter list, then qualifiers / trailing return / initializer list.
    depth = 0
    close = -1
    for idx, ch in enumerate(h):
        if ch == "(":
            if depth == 0 and close < 0:
                open_at = idx
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth == 0 and close < 0:
                close = idx
    if close > 0 and not re.match(r"\s*(=|return\b)", h):
        name_m = FUNC_NAME_RE.search(h[:open_at + 1])
        if name_m and "=" not in h[:open_at]:
            name = name_m.group(1)
            if name not in ("if", "for", "while", "switch", "catch", "return", "sizeof", "decltype"):
                return "function", name
    return "other", None


def in_initializer_list(head):
    """Whether a '{' after `head` initializes a member in a constructor's initializer list (S() : b_{2})."""
    h = head.rstrip()
    if not h or not (h[-1].isalnum() or h[-1] in "_>"):
        return False
    depth, close = 0, -1
    for idx, ch in enumerate(h):
        if ch == "(":
            depth += 1
        elif ch == ")":
            depth -= 1
            if depth == 0:
                close = idx
                break
    if close < 0:
        return False
    rest = h[close + 1:]
    return re.search(r"(?<!:):(?!:)", rest) is not None


def scan(path, text):
    """Yields (kind, name, first line, line count) for each class and top-level function body."""
    clean = strip_comments_and_strings(text)
    stack = []  # (kind, name, line) per open brace
    head_start = 0
    line = 1
    for i, ch in enumerate(clean):
        if ch == "\n":
            line += 1
        elif ch == "{":
            in_function = any(k == "function" for k, _, _ in stack)
            head = clean[head_start:i]
            if not in_function and in_initializer_list(head):
                stack.append(("init", None, line))  # a member's brace initializer: the head goes on
                continue
            kind, name = ("other", None) if in_function else classify(head)
            stack.append((kind, name, line))
            head_start = i + 1
        elif ch == "}":
            if stack:
                kind, name, first = stack.pop()
                if kind == "init":
                    continue
                if kind in ("class", "function"):
                    yield kind, name, first, line - first + 1
            head_start = i + 1
        elif ch == ";":
            head_start = i + 1
        elif ch == ":" and clean[i - 1:i + 1] != "::" and clean[i:i + 2] != "::":
            # Access specifiers (public:) end a head; a constructor's initializer list does not start
            # with one, since its head holds a ')'.
            head = clean[head_start:i].strip()
            if head in ("public", "private", "protected"):
                head_start = i + 1


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--class-limit", type=int, default=250)
    ap.add_argument("--function-limit", type=int, default=80)
    ap.add_argument("--exclude", action="append", default=[], help="file whose findings do not fail the check")
    ap.add_argument("--largest", action="store_true", help="also print the largest class and function found")
    args = ap.parse_args()

    excluded = {os.path.normpath(e) for e in args.exclude}
    failures, excused = [], []
    largest = {"class": (0, ""), "function": (0, "")}
    for root_dir in args.dirs:
        for root, _, files in os.walk(root_dir):
            for f in sorted(files):
                if not f.endswith((".cpp", ".hpp")):
                    continue
                path = os.path.join(root, f)
                with open(path, encoding="utf-8", errors="replace") as fh:
                    text = fh.read()
                is_excluded = os.path.normpath(path) in excluded or f in excluded or \
                    os.path.normpath(os.path.relpath(path, root_dir)) in excluded
                for kind, name, first, count in scan(path, text):
                    limit = args.class_limit if kind == "class" else args.function_limit
                    where = f"{path}:{first}: {kind} {name}: {count} lines"
                    if not is_excluded and count > largest[kind][0]:
                        largest[kind] = (count, where)
                    if count > limit:
                        (excused if is_excluded else failures).append(f"{where} > {limit}")
    for e in excused:
        print("excluded: " + e)
    for f in failures:
        print(f)
    if args.largest:
        for kind in ("class", "function"):
            print(f"largest {kind}: {largest[kind][1] or 'none'}")
    if failures:
        print(f"{len(failures)} bodies over the limits")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

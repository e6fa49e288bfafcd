#!/usr/bin/env python3
"""No function over a set number of lines in the product's C++ (firmware/,
hal/, sim_host/ under ROOT). A function is a brace block at namespace or class level
whose head (the text before its `{`) ends in a parameter list, optionally
followed by qualifiers; lambdas inside it count toward it. Its length is
from the line of its head's name to its closing brace.

  function_length.py [--max N] ROOT      exit 1 and one line per function over N
"""
import argparse
import os
import re
import sys

FOLDERS = ("firmware", "hal", "sim_host")
HEAD = re.compile(r"\)\s*(const|noexcept|override|final|mutable|->\s*[\w:<>,\s*&]+|\s)*$")
CONTROL = re.compile(r"\b(if|for|while|switch|catch|return)\s*\($")


def strip(text):
    """Comments, strings and character literals blanked (line breaks kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i)); i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        elif c in "\"'":
            if c == '"' and i > 0 and text[i - 1] == "R":  # raw string R"d(...)d"
                k = text.find("(", i)
                delim = ")" + text[i + 1:k] + '"'
                j = text.find(delim, k)
                j = n if j < 0 else j + len(delim)
            else:
                j = i + 1
                while j < n and text[j] != c:
                    j += 2 if text[j] == "\\" else 1
                j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j])); i = j
        else:
            out.append(c); i += 1
    return "".join(out)


def functions(path):
    text = strip(open(path, encoding="utf-8", errors="replace").read())
    stack = []  # per open brace: (kind, start line, name)
    head_start = 0
    line = 1
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c == "{":
            head = text[head_start:i].strip()
            inside_function = any(k == "fn" for k, _, _ in stack)
            is_fn = (not inside_function and HEAD.search(head) is not None
                     and not CONTROL.search(head.split("\n")[-1]) and "=" not in head.split("(")[0])
            if is_fn:
                m = re.search(r"([~\w:<>]+)\s*$", head[:head.find("(")])
                name = m.group(1) if m else "?"
                # The head's first line: where its text starts after the last ';' or '}'.
                gap = text[head_start:i]
                start = line - gap.count("\n") + gap[:len(gap) - len(gap.lstrip())].count("\n")
                stack.append(("fn", start, name))
            else:
                stack.append(("block", line, ""))
            head_start = i + 1
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "fn":
                    yield name, start, line
            head_start = i + 1
        elif c == ";":
            head_start = i + 1


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--max", type=int, default=100)
    ap.add_argument("root")
    args = ap.parse_args()
    over = []
    for folder in FOLDERS:
        for dirpath, _, files in os.walk(os.path.join(args.root, folder)):
            for f in sorted(files):
                if not f.endswith((".cpp", ".hpp", ".h", ".cc")):
                    continue
                path = os.path.join(dirpath, f)
                for name, start, end in functions(path):
                    length = end - start + 1
                    if length > args.max:
                        over.append((length, os.path.relpath(path, args.root), start, name))
    for length, path, start, name in sorted(over, reverse=True):
        print(f"{path}:{start}: {name} is {length} lines (at most {args.max})")
    return 1 if over else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""How much of the public API its users use: lists every function declared
in include/volvis/*.h and include/volvis/sys/*.h and counts, for each, the
uses outside the library (src/): the front ends (apps/), the Python package
(python/: calls through cffi's lib, and its C glue), the benchmarks (bench/),
the tests (tests/, fuzz harnesses included) and the examples (examples/).
A public function that none of them uses is a candidate to leave the public
headers (issue 77: "a smaller, unambiguous public API").

What counts as a use: the function's name as an identifier in code, with
comments and (in Python) strings removed; in C sources and headers a
declaration of the same name also counts, so a test that declares a
function by hand still uses it. The Python binding's cdef is generated
from the headers (python/build_ffi.py), so the binding declares every
public function; only its calls count. Notebooks count by their code cells.

Usage: scripts/api-usage.py [--root DIR] [--check PCT] [--used] [--quiet]
  --check PCT  exit 1 when more than PCT % of the public functions are unused,
               or when a per-format reader or writer is public
  --used       list the used functions with their counts too
  --quiet      print the summary line only
Exit status: 0 within the limit (or no --check), 1 over it, 2 usage error.
"""
import argparse
import io
import json
import os
import re
import sys
import tokenize

USER_TREES = ("apps", "python", "bench", "tests", "examples")
# A per-format reader or writer (DESIGN.md, "The door": the format table is
# the way in, so a third-party parser is never reachable around the sandbox):
# never public, whatever its use.
PER_FORMAT_RE = re.compile(
    r"^vv_(?:slc|nrrd|nifti|mhd|vtk|vti|vtp|vtu|raw|tiff|dicom|ome_zarr|zarr|hdf5|bdv|vvb|png|"
    r"plot3d|netcdf|dx|obj|ply|stl|gltf)_(?:read|write)\w*$|^vv_grid_read_\w+$|_write_vvb$")
C_EXT = (".c", ".h", ".cpp", ".cc")
IDENT_RE = re.compile(r"\b[A-Za-z_]\w*\b")


def strip_c(text):
    """C text without comments, string and character literals."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if c == "/" and i + 1 < n and text[i + 1] == "*":
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == "/" and i + 1 < n and text[i + 1] == "/":
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def strip_preprocessor(text):
    lines, out, cont = text.split("\n"), [], False
    for line in lines:
        directive = cont or line.lstrip().startswith("#")
        cont = directive and line.rstrip().endswith("\\")
        out.append("" if directive else line)
    return "\n".join(out)


FUNC_RE = re.compile(r"(?<![\w*(])\b(vv_\w+)\s*\(")


def declared_functions(path):
    """Names of the functions declared (or defined inline) at file scope."""
    text = strip_preprocessor(strip_c(open(path, encoding="utf-8").read()))
    names = []
    depth, stmt = 0, []
    for c in text:
        if depth == 0:
            if c == ";":
                names.extend(function_of("".join(stmt)))
                stmt = []
                continue
            if c == "}":
                continue  # the end of an extern "C" block
            if c == "{":
                head = "".join(stmt)
                if re.fullmatch(r'\s*extern\s*""\s*', head):
                    stmt = []  # extern "C" { ... }: its inside is file scope
                    continue
                # an inline definition's head is a declaration; a struct,
                # union or enum body is not, nor is extern "C"
                if not re.search(r"\b(struct|union|enum)\b[^()]*$", head):
                    names.extend(function_of(head))
                    stmt = []
                else:
                    stmt.append(c)
                depth += 1
                continue
            stmt.append(c)
        else:
            if c == "{":
                depth += 1
            elif c == "}":
                depth -= 1
                if depth == 0:
                    # after an inline body the statement ends; after a
                    # struct body the declarator and ';' follow
                    if stmt and not re.search(r"\b(struct|union|enum)\b", "".join(stmt)):
                        stmt = []
                    continue
            if stmt:
                stmt.append(c)
    return names


def function_of(stmt):
    s = " ".join(stmt.split())
    if not s or s.startswith("typedef"):
        return []
    # a struct or enum definition's declarator is not a function
    s = re.sub(r"\b(struct|union|enum)\b[^;{]*\{.*\}", "", s)
    m = FUNC_RE.search(s)
    if not m:
        return []
    # the name must be the declarator: not inside parentheses (a function
    # pointer's parameter list) and not after '=' (an initializer)
    before = s[: m.start()]
    if before.count("(") != before.count(")") or "=" in before:
        return []
    return [m.group(1)]


def public_api(root):
    funcs = {}  # name -> header (relative)
    inc = os.path.join(root, "include", "volvis")
    for sub in ("", "sys"):
        d = os.path.join(inc, sub)
        for n in sorted(os.listdir(d)):
            if n.endswith(".h"):
                rel = os.path.join("include", "volvis", sub, n).replace(os.sep, "/")
                rel = rel.replace("volvis//", "volvis/")
                for name in declared_functions(os.path.join(d, n)):
                    funcs.setdefault(name, rel)
    return funcs


def python_identifiers(text):
    """NAME tokens of Python source: code only, no strings or comments."""
    names = []
    try:
        for tok in tokenize.generate_tokens(io.StringIO(text).readline):
            if tok.type == tokenize.NAME:
                names.append(tok.string)
    except (tokenize.TokenError, IndentationError, SyntaxError):
        names = IDENT_RE.findall(re.sub(r"#.*", "", text))
    return names


def user_files(root):
    for top in USER_TREES:
        for d, dirs, files in os.walk(os.path.join(root, top)):
            dirs[:] = sorted(x for x in dirs if x not in ("__pycache__", ".git", "corpus"))
            for n in sorted(files):
                yield os.path.join(d, n)


def count_uses(root, funcs):
    counts = {name: 0 for name in funcs}
    where = {name: set() for name in funcs}
    for path in user_files(root):
        rel = os.path.relpath(path, root)
        try:
            text = open(path, encoding="utf-8").read()
        except (UnicodeDecodeError, OSError):
            continue
        if path.endswith(C_EXT):
            idents = IDENT_RE.findall(strip_c(text))
        elif path.endswith(".py"):
            idents = python_identifiers(text)
        elif path.endswith(".ipynb"):
            try:
                cells = json.loads(text).get("cells", [])
            except ValueError:
                continue
            idents = []
            for cell in cells:
                if cell.get("cell_type") == "code":
                    src = cell.get("source", "")
                    idents += python_identifiers("".join(src) if isinstance(src, list) else src)
        else:
            continue
        for ident in idents:
            if ident in counts:
                counts[ident] += 1
                where[ident].add(rel.split(os.sep)[0])
    return counts, where


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    ap.add_argument("--check", type=float, metavar="PCT")
    ap.add_argument("--used", action="store_true")
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    root = os.path.abspath(args.root)
    funcs = public_api(root)
    if not funcs:
        print("api-usage: no public functions found under %s/include/volvis" % root)
        return 2
    counts, where = count_uses(root, funcs)
    unused = sorted(n for n in funcs if counts[n] == 0)
    pct = 100.0 * len(unused) / len(funcs)
    if not args.quiet:
        by_header = {}
        for n in unused:
            by_header.setdefault(funcs[n], []).append(n)
        for h in sorted(by_header):
            print("%s:" % h)
            for n in by_header[h]:
                print("  %s" % n)
        if args.used:
            print("used:")
            for n in sorted(funcs, key=lambda x: (funcs[x], x)):
                if counts[n]:
                    print("  %-44s %5d  %s" % (n, counts[n], " ".join(sorted(where[n]))))
    headers = len(set(funcs.values()))
    print("api-usage: %d public functions in %d headers, %d unused by apps, python, bench, "
          "tests and examples (%.1f %%)" % (len(funcs), headers, len(unused), pct))
    per_format = sorted(n for n in funcs if PER_FORMAT_RE.search(n))
    for n in per_format:
        print("api-usage: %s: %s is a per-format entry point: the format table is the way in "
              "(move it to src/io/io_internal.h)" % (funcs[n], n))
    if args.check is not None and (pct > args.check or per_format):
        if pct > args.check:
            print("api-usage: %.1f %% unused is over the limit of %g %%" % (pct, args.check))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

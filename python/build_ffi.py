#!/usr/bin/env python3
"""Generates the C source of the volvis._volvis extension (cffi, API mode,
out of line) from the public headers, so the headers stay the one source of
truth for the binding's declarations.

Usage: build_ffi.py CC INCLUDE_DIR GLUE_C OUT_C [OUT_CDEF]

How (docs/python.md, "How the binding is built"):
 1. The C compiler's preprocessor expands include/volvis/volvis.h (and
    include/volvis/sys/*.h where present) with empty stand-ins for
    <stddef.h> and <stdint.h> (cffi knows size_t, uint8_t, ... itself) and
    without __attribute__, keeping line markers.
 2. pycparser (cffi's own parser) reads the result; declarations that come
    from the stand-ins are dropped, and the one `static inline` function
    (vv_voxel_value) becomes a plain declaration (API mode calls the real
    inline function through a generated wrapper).
 3. The object-like #define constants of the headers are added: integer ones
    as `#define NAME ...` and floating ones as `static const double NAME;`,
    both filled in by the compiler from the real header.
 4. cffi's FFI.emit_c_code writes the extension's C source, which CMake
    compiles against the real headers and links with libvolvis; the
    compiler checks every struct layout against them, so a drift is a build
    error, never a silent mismatch.
"""
import glob
import os
import re
import subprocess
import sys
import tempfile

import cffi
import pycparser
from pycparser import c_ast, c_generator

# Types the stand-in headers declare so pycparser can parse; cffi knows them.
STANDARD_TYPES = [
    "size_t", "ptrdiff_t", "int8_t", "int16_t", "int32_t", "int64_t", "uint8_t", "uint16_t",
    "uint32_t", "uint64_t", "intptr_t", "uintptr_t",
]


def preprocess(cc, include_dir, headers):
    with tempfile.TemporaryDirectory() as fake:
        for name in ("stddef.h", "stdint.h"):
            with open(os.path.join(fake, name), "w") as f:
                f.write("#pragma once\n")
                for t in STANDARD_TYPES:
                    f.write("typedef int %s;\n" % t)
        # the inline helpers of include/volvis/sys/renderer.h use sqrt and
        # INFINITY in their bodies, which become declarations only
        with open(os.path.join(fake, "math.h"), "w") as f:
            f.write("#pragma once\ndouble sqrt(double);\n"
                    "#define INFINITY (__builtin_inff())\n#define NAN (__builtin_nanf(\"\"))\n")
        src = os.path.join(fake, "all.h")
        with open(src, "w") as f:
            for h in headers:
                f.write('#include "%s"\n' % os.path.abspath(h))
        cmd = [cc, "-E", "-nostdinc", "-I", fake, "-I", include_dir, "-D__attribute__(x)=",
               "-D__extension__=", "-std=c11", src]
        out = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
        return out, fake


def _has_const(node):
    while not isinstance(node, c_ast.TypeDecl):
        node = node.type
    return "const" in node.quals


def _simplify_params(node):
    """cffi emits broken C for parameters that are pointers to arrays
    (`const int (*seeds)[3]`, `const double m[3][3]`): declare them as
    `void *` (`const void *`), which C converts implicitly in the call the
    generated wrapper makes to the real function."""
    funcs = []

    class V(c_ast.NodeVisitor):
        def visit_FuncDecl(self, n):
            funcs.append(n)
            self.generic_visit(n)
    V().visit(node)
    for f in funcs:
        if f.args is None:
            continue
        for i, p in enumerate(f.args.params):
            if not isinstance(p, c_ast.Decl):
                continue
            t = p.type
            if isinstance(t, (c_ast.PtrDecl, c_ast.ArrayDecl)) and isinstance(t.type,
                                                                           c_ast.ArrayDecl):
                quals = ["const"] if _has_const(t) else []
                p.type = c_ast.PtrDecl([], c_ast.TypeDecl(p.name, quals, None,
                                                          c_ast.IdentifierType(["void"])))


def declarations(text, include_dir):
    ast = pycparser.CParser().parse(text, "volvis.h")
    gen = c_generator.CGenerator()
    inc = os.path.realpath(include_dir)
    out = []
    for node in ast.ext:
        coord = node.coord.file if node.coord else ""
        if not os.path.realpath(coord).startswith(inc + os.sep):
            continue  # the stand-in standard headers
        _simplify_params(node)
        if isinstance(node, c_ast.FuncDef):
            decl = node.decl
            decl.storage = [s for s in decl.storage if s != "static"]
            decl.funcspec = [s for s in decl.funcspec if s != "inline"]
            out.append(gen.visit(decl) + ";")
        else:
            out.append(gen.visit(node) + ";")
    return "\n".join(out) + "\n"


DEFINE = re.compile(r"^#define\s+(VV_[A-Z0-9_]+)[ \t]+([^/\n]+?)\s*(/\*.*)?$", re.M)


def constants(headers):
    """Object-like VV_ macros: integers as '#define N ...', floats as constants."""
    out = []
    seen = set()
    for h in headers:
        with open(h) as f:
            for name, value, _ in DEFINE.findall(f.read()):
                if name in seen or "(" in name:
                    continue
                seen.add(name)
                plain = re.sub(r"\((?:uint64_t|size_t|int|unsigned)\)", "", value)
                plain = re.sub(r"(?<=\d)[uUlL]+\b", "", plain)
                try:
                    v = eval(plain, {"__builtins__": {}})
                except Exception:
                    continue  # not a plain number (e.g. a macro of macros): leave it out
                if isinstance(v, float):
                    out.append("static const double %s;" % name)
                elif isinstance(v, int):
                    out.append("#define %s ..." % name)
    return "\n".join(out) + "\n"


GLUE_CDEF = """
typedef struct vvpy_progress_state vvpy_progress_state;
vvpy_progress_state *vvpy_progress_new(void);
void vvpy_progress_free(vvpy_progress_state *s);
vv_progress vvpy_progress_get(vvpy_progress_state *s);
double vvpy_progress_fraction(const vvpy_progress_state *s);
int vvpy_progress_calls(const vvpy_progress_state *s);
void vvpy_progress_cancel(vvpy_progress_state *s);
uint64_t vvpy_hash(const void *data, size_t n);
void vvpy_free(void *p);
extern "Python" void vvpy_release(void *user, void *data);
"""


def main(argv):
    if len(argv) not in (5, 6):
        sys.exit("usage: build_ffi.py CC INCLUDE_DIR GLUE_C OUT_C [OUT_CDEF]")
    cc, include_dir, glue_c, out_c = argv[1:5]
    headers = [os.path.join(include_dir, "volvis", "volvis.h")]
    headers += sorted(glob.glob(os.path.join(include_dir, "volvis", "sys", "*.h")))
    text, _ = preprocess(cc, include_dir, headers)
    cdef = declarations(text, include_dir)
    all_headers = sorted(glob.glob(os.path.join(include_dir, "volvis", "*.h")))
    all_headers += sorted(glob.glob(os.path.join(include_dir, "volvis", "sys", "*.h")))
    cdef += constants(all_headers)
    cdef += GLUE_CDEF
    if len(argv) == 6:
        with open(argv[5] + ".tmp", "w") as f:
            f.write(cdef)
        os.replace(argv[5] + ".tmp", argv[5])
    ffi = cffi.FFI()
    ffi.cdef(cdef)
    with open(glue_c) as f:
        glue = f.read()
    incs = "#include <volvis/volvis.h>\n"
    for h in headers[1:]:
        incs += "#include <volvis/sys/%s>\n" % os.path.basename(h)
    ffi.set_source("volvis._volvis", incs + glue)
    tmp = out_c + ".tmp.c"
    ffi.emit_c_code(tmp)
    os.replace(tmp, out_c)


if __name__ == "__main__":
    main(sys.argv)

#!/usr/bin/env python3
"""Which lines of our own parsers a run reaches, and which error messages it
never formats.

Source-based coverage (clang's -fprofile-instr-generate -fcoverage-mapping):
run programs built with it under LLVM_PROFILE_FILE, merge the raw profiles
with llvm-profdata, read the line counts with llvm-cov. Two uses:

  # the test suite (the coverage preset: cmake --preset coverage, build):
  scripts/coverage.py tests -R 'test_io_|test_scene_' [--build build/coverage]

  # the fuzz harnesses over their corpora (scripts/fuzz.sh --coverage):
  scripts/coverage.py profiles --build build/fuzzcov --profiles DIR --objects BIN...

Both print, per file of --files (default: our own parsers, PARSERS below),
the lines reached out of the lines with code, and every call that formats an
error (vv_error_set, vv_error_prefix, or --pattern) on a line never run, as
file:line: text. --markdown writes the table for docs/security.md; --fail
exits 1 when an error call is unreached.

Counts are per line: a line with two error calls (a ternary) counts as
reached when either runs. In the coverage preset the DICOM reader (GDCM)
is stopped by the sandbox's filter (a system call clang's runtime makes on
its path), so test_io_dicom and the DICOM parts of the CLI tests fail
there; the release and asan presets run them.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

# Our own parsers (issue 67): what reads a file's bytes or metadata in the
# process without a third-party library doing the parsing.
PARSERS = [
    "src/io/volume/slc.c", "src/io/volume/mhd.c", "src/io/volume/vtk_legacy.c",
    "src/io/grid/grid_vtk.c", "src/io/grid/grid_plot3d.c", "src/io/grid/grid_dx.c",
    "src/io/volume/raw.c", "src/compress/vvc_format.c", "src/io/store/vvb.c",
    "src/io/store/vvb_read.c", "src/io/store/bricked.c", "src/io/store/zarr_read.c",
    "src/io/store/zarr_pyramid.c", "src/io/store/zarr3.c", "src/io/store/bdv_xml.c",
    "src/io/store/hdf5_pyramid.c", "src/io/store/pyramid_open.c",
    "src/io/store/pyramid_load.c", "src/scene/scene.c", "src/scene/scene_appearance.c",
    "src/scene/scene_channels.c", "src/scene/scene_fields.c",
    "src/scene/scene_geometry.c", "src/scene/scene_objects.c",
    "src/manipulate/animation_json.c", "src/input/net.c", "src/input/replay.c",
]

# The calls that format an error: the library's, and the parsers' own
# helpers (the scene's and the animation's field errors, the replay's
# lines, the network protocol's replies and warnings).
ERROR_CALL = (r"\bvv_error_(set|prefix)\s*\(|\bvv_scene_(serr|missing)\s*\(c,|\baerr\s*\(c,"
              r"|\bbad\s*\(path,|\bvv_input_warn\s*\(m,|snprintf\(err,")


def tool(name):
    for cand in (name + "-14", name):
        path = shutil.which(cand)
        if path:
            return path
    sys.exit(f"coverage.py: {name} (llvm-14) is not installed")


def instrumented(build):
    """Every executable and shared library under @build built with coverage."""
    found = []
    for root, _dirs, files in os.walk(build):
        if "/CMakeFiles" in root or "/prof" in root:
            continue
        for f in files:
            p = os.path.join(root, f)
            if not os.path.isfile(p) or os.path.islink(p):
                continue
            if not (os.access(p, os.X_OK) or f.endswith(".so")):
                continue
            with open(p, "rb") as fh:
                if fh.read(4) != b"\x7fELF":
                    continue
            out = subprocess.run(["readelf", "-S", "-W", p], capture_output=True, text=True).stdout
            if "__llvm_covmap" in out:
                found.append(p)
    return sorted(found)


def merge(profiles_dir, out):
    raws = [os.path.join(profiles_dir, f) for f in os.listdir(profiles_dir) if f.endswith(".profraw")]
    if not raws:
        sys.exit(f"coverage.py: no .profraw under {profiles_dir}")
    lst = out + ".list"
    with open(lst, "w") as fh:
        fh.write("\n".join(raws) + "\n")
    subprocess.run([tool("llvm-profdata"), "merge", "-sparse", "-f", lst, "-o", out], check=True)


def parse_count(text):
    text = text.strip()
    if not text:
        return None
    mult = {"k": 1e3, "M": 1e6, "G": 1e9, "T": 1e12, "P": 1e15, "E": 1e18}.get(text[-1], 1)
    return float(text[:-1] if mult != 1 else text) * mult


def line_counts(profdata, objects, files, root):
    """{file: {line: count}} for the lines llvm-cov maps (holding code)."""
    cmd = [tool("llvm-cov"), "show", "-format=text", "-instr-profile", profdata, objects[0]]
    for o in objects[1:]:
        cmd += ["-object", o]
    cmd += [os.path.join(root, f) for f in files]
    text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    counts = {}
    # one file: llvm-cov prints no header before its lines
    cur = counts.setdefault(files[0], {}) if len(files) == 1 else None
    for line in text.split("\n"):
        m = re.match(r"^\s*(\d+)\|([^|]*)\|", line)
        if m and cur is not None:
            c = parse_count(m.group(2))
            if c is not None:
                ln = int(m.group(1))
                cur[ln] = max(cur.get(ln, 0), c)
            continue
        if line.endswith(":") and line.startswith("/"):
            cur = counts.setdefault(os.path.relpath(line[:-1], root), {})
    return counts


def code_lines(path):
    """Line numbers holding code: not blank, not only a comment or a brace."""
    text = open(path, encoding="utf-8", errors="replace").read()
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    out = {}
    for i, l in enumerate(text.split("\n"), 1):
        s = re.sub(r"//.*", "", l).strip()
        if s and s not in ("{", "}", "};", "} else {", "else", "break;") and not s.startswith("#"):
            out[i] = s
    return out


def report(counts, files, root, pattern, markdown):
    rows, unreached = [], []
    tot_code = tot_hit = 0
    for f in files:
        src = os.path.join(root, f)
        if not os.path.exists(src):
            continue
        c = counts.get(f, {})
        code = code_lines(src)
        measured = [ln for ln in code if ln in c]
        hit = [ln for ln in measured if c[ln] > 0]
        tot_code += len(measured)
        tot_hit += len(hit)
        raw = open(src, encoding="utf-8", errors="replace").read().split("\n")
        errs = [i for i, l in enumerate(raw, 1) if re.search(pattern, l) and not l.strip().startswith(("*", "/*", "//"))]
        missed = [i for i in errs if c.get(i, 0) == 0]
        unreached += [f"{f}:{i}: {raw[i - 1].strip()}" for i in missed]
        rows.append((f, len(hit), len(measured), len(errs) - len(missed), len(errs)))
    if markdown:
        print("| file | lines reached | error calls reached |")
        print("|---|---|---|")
        for f, h, m, eh, en in rows:
            pct = 100.0 * h / m if m else 0
            print(f"| `{f}` | {h}/{m} ({pct:.1f} %) | {eh}/{en} |")
        pct = 100.0 * tot_hit / tot_code if tot_code else 0
        print(f"| **all** | {tot_hit}/{tot_code} ({pct:.1f} %) | {sum(r[3] for r in rows)}/{sum(r[4] for r in rows)} |")
    else:
        for f, h, m, eh, en in rows:
            pct = 100.0 * h / m if m else 0
            print(f"{f:40s} lines {h:5d}/{m:5d} {pct:5.1f} %   error calls {eh:4d}/{en:4d}")
        pct = 100.0 * tot_hit / tot_code if tot_code else 0
        print(f"{'all':40s} lines {tot_hit:5d}/{tot_code:5d} {pct:5.1f} %")
    if unreached:
        print(f"\n{len(unreached)} error calls never run:", file=sys.stderr if markdown else sys.stdout)
        for u in unreached:
            print("  " + u, file=sys.stderr if markdown else sys.stdout)
    return unreached


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", choices=["tests", "profiles"])
    ap.add_argument("--build", default="build/coverage")
    ap.add_argument("-R", dest="regex", default="", help="ctest -R (tests mode)")
    ap.add_argument("--profiles", help="folder of .profraw (profiles mode)")
    ap.add_argument("--objects", nargs="*", help="instrumented programs (default: all under --build)")
    ap.add_argument("--files", nargs="*", default=PARSERS)
    ap.add_argument("--pattern", default=ERROR_CALL)
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--fail", action="store_true")
    a = ap.parse_args()
    root = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
    build = os.path.abspath(a.build)
    work = tempfile.mkdtemp(prefix="vvcov-")
    try:
        if a.mode == "tests":
            prof = os.path.join(work, "raw")
            os.makedirs(prof)
            env = dict(os.environ, LLVM_PROFILE_FILE=os.path.join(prof, "%p-%m.profraw"))
            # clang's OpenMP runtime sets thread affinity, which the reader
            # sandbox forbids, and keeps its thread descriptors to the end
            env.setdefault("KMP_AFFINITY", "disabled")
            env.setdefault("LSAN_OPTIONS", "suppressions=" + os.path.join(root, "tests/lsan.supp") + ":print_suppressions=0")
            env.setdefault("ASAN_OPTIONS", "detect_leaks=1:abort_on_error=1")
            env.setdefault("UBSAN_OPTIONS", "print_stacktrace=1:halt_on_error=1")
            cmd = ["ctest", "--test-dir", build, "--output-on-failure", "-j2"]
            if a.regex:
                cmd += ["-R", a.regex]
            rc = subprocess.run(cmd, env=env).returncode
            if rc:
                print(f"coverage.py: ctest failed (exit {rc}); the report covers what ran", file=sys.stderr)
        else:
            prof = a.profiles
        profdata = os.path.join(work, "merged.profdata")
        merge(prof, profdata)
        objects = a.objects or instrumented(build)
        if not objects:
            sys.exit(f"coverage.py: no instrumented programs under {build}")
        counts = line_counts(profdata, objects, a.files, root)
        missed = report(counts, a.files, root, a.pattern, a.markdown)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return 1 if (a.fail and missed) else 0


if __name__ == "__main__":
    sys.exit(main())

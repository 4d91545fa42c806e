#!/usr/bin/env python3
"""The include-direction check: every #include under src/, apps/ and
include/volvis/ must point down the layer map (docs/architecture.md), or sideways to a
sibling's public header, never up and never into a sibling's private header.
With --objects BUILD_DIR the same rules are checked on the calls themselves:
every vv_ function an object file of the build uses must be defined in its
own component or below, and a function of another component (core excepted)
must be declared in include/volvis/ (a header can be avoided by declaring
a function by hand; a call cannot).
The GUI's names are checked too: apps/volvis-gui/ names its own functions,
types and macros vvg_/Vvg/VVG_ (docs/architecture.md), so every vv_, Vv or VV_ name
its files use must be one the library declares in include/volvis/.

    apps, python -> scene -> manipulate, parallel -> render, modeling, filter,
    measure, surface, compress, input, io -> model, sandbox -> core

Rules (docs/architecture.md, "Layers"; python/ and apps/ are programs):

1. A file may include a public header (include/volvis/...) of its own
   component, of a sibling (same layer) or of any lower layer. Never of a
   higher layer. include/volvis/volvis.h (everything) is for apps only.
2. A component's private headers (any header under src/<component>/) are its
   own. The one exception is core: src/core/*.h are the library's private
   toolbox (the atomic file writer, the JSON text helpers, the grid and
   brick internals) and every component of src/ may include them; apps may
   not (they see the installed API only).
3. Inside src/render, a renderer (src/render/<name>/) includes the shared
   render code (src/render/*.h), never another renderer's files.
4. The GUI (apps/volvis-gui/) defines no name with the library's prefix:
   a vv_/Vv/VV_ name in its files (code or comment) is the library's,
   declared in include/volvis/; its own are vvg_/Vvg/VVG_, in files named
   vvg-*.c/.h.

The layer map is the LAYERS and PUBLIC tables below: the one place that says
which component sits where. Known violations that another piece of work is
removing are listed in PENDING with the reason; they are reported on every
run and do not fail the check, but an entry that no longer matches a
violation does fail it, so the list shrinks as the work lands.

Usage: scripts/check-includes.py [--root DIR] [--objects BUILD_DIR] [--quiet]
Exit status: 0 clean (pending entries only), 1 a violation or a stale
pending entry, 2 usage error.
"""
import argparse
import os
import re
import subprocess
import sys

# ---- the layer map (lower number = lower layer) ---------------------------
LAYERS = {
    "core": 0,
    "model": 1, "sandbox": 1,  # the sandbox: a transport under the format table (io)
    "io": 2, "render": 2, "modeling": 2, "filter": 2, "measure": 2,
    "surface": 2, "compress": 2, "input": 2,
    "manipulate": 3, "parallel": 3,
    "scene": 4,
    "apps": 5, "python": 5,
}

# Public headers (include/volvis/<name>) and the component that implements
# them. include/volvis/sys/ (the implementor's API) is mapped the same way.
PUBLIC = {
    "core.h": "core", "math.h": "core", "volume.h": "core", "image.h": "core",
    "mesh.h": "core", "grid.h": "core",
    "source.h": "core",  # volume sources and the cache: io opens them, model holds them
    "sys/source.h": "core",  # the source table and the drivers' views: io serves, render reads
    "model.h": "model",
    "io.h": "io", "video.h": "io", "sys/format.h": "io", "bricks.h": "io",
    "sys/sandbox.h": "sandbox",  # the transport io's third-party rows go through
    "render.h": "render", "raster.h": "render", "radiosity.h": "render", "slice.h": "render",
    "sys/renderer.h": "render", "sys/geometry.h": "model",
    "modeling.h": "modeling",
    "filter.h": "filter",
    "measure.h": "measure",
    "surface.h": "surface",
    "compress.h": "compress",
    "input.h": "input",
    "navigator.h": "manipulate", "animate.h": "manipulate",
    "parallel.h": "parallel",
    "scene.h": "scene",
    "volvis.h": "apps",  # the umbrella header: apps and python only
}

# Known violations being removed by other work of issue 27: (including file,
# included header as written) -> reason. Reported, not failed; a stale entry
# fails.
PENDING = {
}

# Calls the same pieces of work are removing: (object's source, symbol) -> reason.
PENDING_CALLS = {
}

# "header", and <volvis/header> (the installed spelling, which the GUI uses)
INCLUDE_RE = re.compile(r'^[ \t]*#[ \t]*include[ \t]*(?:"([^"]+)"|<(volvis/[^>]+)>)', re.M)
SOURCE_EXT = (".c", ".h", ".cpp")


def component_of(rel):
    """(component, subcomponent) of a repository-relative path, or None."""
    parts = rel.split("/")
    if parts[0] == "src" and len(parts) >= 3:
        sub = parts[2] if parts[1] == "render" and len(parts) >= 4 else None
        return parts[1], sub
    if parts[0] in ("apps", "python"):
        return parts[0], parts[1] if len(parts) > 2 else None
    if parts[0] == "include" and len(parts) >= 3 and parts[1] == "volvis":
        name = "/".join(parts[2:])
        return PUBLIC.get(name), None
    return None


def resolve(root, including, inc):
    """Repository-relative path of the header @inc as the compiler finds it:
    beside the including file, then under src/, then include/."""
    here = os.path.dirname(including)
    for base in (here, "src", "include", os.path.join("include", "volvis")):
        cand = os.path.normpath(os.path.join(base, inc))
        if os.path.isfile(os.path.join(root, cand)):
            return cand.replace(os.sep, "/")
    return None


def check_one(rel, inc, target):
    """A message when the include of @target (resolved) from @rel breaks a
    rule, else None."""
    src_comp, src_sub = component_of(rel)
    if src_comp is None:
        return "%s: not in the layer map (add it to LAYERS or PUBLIC)" % rel
    tparts = target.split("/")
    if tparts[0] == "include":
        name = "/".join(tparts[2:])
        comp = PUBLIC.get(name)
        if comp is None:
            return "public header %s is not in the layer map (PUBLIC)" % name
        if LAYERS[comp] > LAYERS[src_comp] or (comp == "apps" and src_comp != "apps"):
            return "points up: %s (%s, layer %d) includes %s of %s (layer %d)" % (
                rel, src_comp, LAYERS[src_comp], name, comp, LAYERS[comp])
        return None
    if tparts[0] == "src":
        comp = tparts[1]
        if comp not in LAYERS:
            return "%s: component %s is not in the layer map" % (target, comp)
        if src_comp in ("apps", "python"):
            return "%s includes the library-private header %s (apps see include/volvis only)" % (
                rel, target)
        if comp == src_comp:
            if comp == "render" and src_sub and len(tparts) >= 4 and tparts[2] != src_sub:
                return "renderer %s includes another renderer's file %s" % (src_sub, target)
            return None
        if comp == "core":
            return None
        if LAYERS[comp] > LAYERS[src_comp]:
            return "points up: %s (%s) includes %s's private header %s" % (
                rel, src_comp, comp, target)
        return "%s (%s) includes %s's private header %s (use its public header)" % (
            rel, src_comp, comp, target)
    if tparts[0] in ("apps", "python"):
        if src_comp == tparts[0] and (src_sub is None or tparts[1] == src_sub):
            return None
        return "%s includes %s, another program's file" % (rel, target)
    return None


def scan(root):
    files = []
    for top in ("src", "apps", "python", os.path.join("include", "volvis")):
        for d, _, names in os.walk(os.path.join(root, top)):
            for n in names:
                if n.endswith(SOURCE_EXT):
                    files.append(os.path.relpath(os.path.join(d, n), root).replace(os.sep, "/"))
    files.sort()
    found = []  # (rel, inc, message)
    for rel in files:
        with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
            text = f.read()
        for m in INCLUDE_RE.finditer(text):
            inc = m.group(1) or m.group(2)
            target = resolve(root, rel, inc)
            if target is None:
                continue  # a generated header (vv_version.h) or a system one in quotes
            msg = check_one(rel, inc, target)
            if msg:
                line = text.count("\n", 0, m.start()) + 1
                found.append((rel, inc, "%s:%d: %s" % (rel, line, msg)))
    return len(files), found


# The GUI's own prefix is vvg_ (Vvg types, VVG_ macros); vv_ is the library's.
GUI_DIR = os.path.join("apps", "volvis-gui")
LIB_NAME_RE = re.compile(r"\b(?:vv_|VV_|Vv(?!g[A-Z0-9]))\w+")


def public_names(root):
    """Every vv_/Vv/VV_ name in include/volvis/ (comments removed first):
    functions, types, enum values and macros."""
    names = set()
    for d, _, files in os.walk(os.path.join(root, "include", "volvis")):
        for n in files:
            if n.endswith(".h"):
                with open(os.path.join(d, n), encoding="utf-8", errors="replace") as f:
                    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", f.read(), flags=re.S)
                names.update(LIB_NAME_RE.findall(text))
    return names


def scan_gui_names(root):
    """(rel, name, message) for every vv_/Vv/VV_ name in the GUI's files that
    the library does not declare: a GUI name with the library's prefix."""
    public = public_names(root)
    found = []
    for d, _, names in os.walk(os.path.join(root, GUI_DIR)):
        for n in sorted(names):
            if not n.endswith(SOURCE_EXT):
                continue
            rel = os.path.relpath(os.path.join(d, n), root).replace(os.sep, "/")
            if n.startswith("vv-"):
                found.append((rel, n, "%s: the GUI's files are vvg-*.c/.h" % rel))
            with open(os.path.join(root, rel), encoding="utf-8", errors="replace") as f:
                text = f.read()
            seen = set()
            for m in LIB_NAME_RE.finditer(text):
                name = m.group(0)
                if name in public or name in seen:
                    continue
                seen.add(name)
                line = text.count("\n", 0, m.start()) + 1
                found.append((rel, name, "%s:%d: %s is not the library's (include/volvis/): "
                              "the GUI's own names are vvg_/Vvg/VVG_" % (rel, line, name)))
    return found


def public_functions(root):
    """Names declared in include/volvis/ (comments removed first)."""
    names = set()
    for d, _, files in os.walk(os.path.join(root, "include", "volvis")):
        for n in files:
            if n.endswith(".h"):
                with open(os.path.join(d, n), encoding="utf-8", errors="replace") as f:
                    text = re.sub(r"/\*.*?\*/|//[^\n]*", " ", f.read(), flags=re.S)
                names.update(re.findall(r"\b(vv_\w+)\s*\(", text))
    return names


def nm_symbols(paths):
    """{path: [(symbol, type)]} of every external symbol of the objects, one nm
    for all of them (one nm an object took 90 ms each, 35 s a build)."""
    out = {p: [] for p in paths}
    for i in range(0, len(paths), 500):
        batch = paths[i:i + 500]
        text = subprocess.run(["nm", "-P", "-A", "--extern-only"] + batch, capture_output=True,
                              text=True, check=True).stdout
        for line in text.splitlines():
            path, sep, rest = line.rpartition(": ")
            f = rest.split()
            if sep and len(f) >= 2 and path in out:
                out[path].append((f[0], f[1]))
    return out


def object_source(build, obj):
    """Repository-relative source of an object file of the build, or None."""
    rel = os.path.relpath(obj, build).replace(os.sep, "/")
    m = re.match(r"CMakeFiles/volvis_obj\.dir/(src/.*)\.o$", rel)
    if m:
        return m.group(1)
    m = re.match(r"(apps/[^/]+)/CMakeFiles/[^/]+\.dir/(.*)\.o$", rel)
    if m:
        return m.group(1) + "/" + m.group(2)
    return None


def scan_objects(root, build):
    """(rel, symbol, message) for every call against the map."""
    objs = []
    for top in ("CMakeFiles/volvis_obj.dir/src", "apps"):
        for d, _, names in os.walk(os.path.join(build, top)):
            for n in names:
                if n.endswith(".o"):
                    src = object_source(build, os.path.join(d, n))
                    # objects of sources since moved or removed stay in a build folder
                    if src and os.path.isfile(os.path.join(root, src)):
                        objs.append((src, os.path.join(d, n)))
    if not any(src.startswith("src/") for src, _ in objs):
        raise SystemExit("check-includes: no library objects under %s (build it first)" % build)
    defined, used = {}, []
    symbols = nm_symbols([path for _, path in objs])
    for src, path in objs:
        for sym, kind in symbols[path]:
            if not sym.startswith("vv_"):
                continue
            if kind == "U":
                used.append((src, sym))
            elif kind in "TDBRVW":
                defined[sym] = src
    public = public_functions(root)
    found = []
    for src, sym in sorted(set(used)):
        if sym not in defined:
            continue
        me, _ = component_of(src)
        them, _ = component_of(defined[sym])
        if me == them or them == "core" and me not in ("apps", "python"):
            continue
        if LAYERS[them] > LAYERS[me]:
            found.append((src, sym, "%s (%s) calls %s of %s (%s): points up" % (
                src, me, sym, them, defined[sym])))
        elif sym not in public:
            found.append((src, sym, "%s (%s) calls %s, %s's unpublished function (%s)" % (
                src, me, sym, them, defined[sym])))
    return len(objs), found


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=os.path.join(os.path.dirname(__file__), ".."))
    ap.add_argument("--objects", metavar="BUILD_DIR",
                    help="also check the calls of the object files of this build")
    ap.add_argument("--quiet", action="store_true", help="print failures only")
    a = ap.parse_args()
    root = os.path.abspath(a.root)
    n_files, found = scan(root)
    failures = []
    n_pending = sort_out(found, PENDING, "includes", failures, a.quiet)
    failures += [msg for _, _, msg in scan_gui_names(root)]
    summary = "%d files" % n_files
    if a.objects:
        n_objs, calls = scan_objects(root, os.path.abspath(a.objects))
        n_pending += sort_out(calls, PENDING_CALLS, "calls", failures, a.quiet)
        summary += ", %d object files" % n_objs
    for msg in failures:
        print("error: " + msg)
    if not a.quiet or failures:
        print("check-includes: %s, %d violations, %d pending (%s)" % (
            summary, len(failures), n_pending, "FAILED" if failures else "ok"))
    return 1 if failures else 0


def sort_out(found, pending, verb, failures, quiet):
    """Reports pending violations, adds the others and stale pending entries
    to @failures; returns the number of pending violations seen."""
    hit = set()
    for rel, what, msg in found:
        if (rel, what) in pending:
            hit.add((rel, what))
            if not quiet:
                print("pending: %s [%s]" % (msg, pending[(rel, what)]))
        else:
            failures.append(msg)
    for rel, what in sorted(set(pending) - hit):
        failures.append("stale pending entry: %s no longer %s %s against the map; remove it "
                        "from scripts/check-includes.py" % (rel, verb, what))
    return len(hit)


if __name__ == "__main__":
    sys.exit(main())

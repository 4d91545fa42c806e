#!/usr/bin/env python3
"""The picture of the house (docs/architecture.md), generated from the tree:
the folders of src/ and the front ends as nodes, an arrow A -> B where a file
of A includes a header of B.

    scripts/architecture-graph.py [--root DIR] [--check] [--svg] [--cycles]

Where the nodes and layers come from: scripts/check-includes.py, whose
LAYERS and PUBLIC tables are the one layer map (a public header
include/volvis/<name> belongs to PUBLIC[name]; a private header to the
folder of src/ it is in). The files read:

- every .c/.h of src/<folder>/ (a node each) and of include/volvis/ (a
  public header's includes are its component's);
- the front ends: apps/volvis/ (the CLI), apps/volvis/serve/ (serve),
  apps/volvis-gui/ (the GUI), apps/volvis-reader/ (the reader process),
  python/ (the cffi package) and web/ (the browser client);
- a front end that includes the umbrella header volvis/volvis.h (which
  would make an arrow to every folder), and python/, whose cffi module is
  compiled over all public headers, are resolved by use: an arrow to the
  component of each public header that declares a vv_/Vv/VV_ name the
  front end's files use (code only; for Python, names after `lib.` and in
  `ffi` type strings);
- two arrows that are not includes, drawn dashed and found in the tree too:
  web -> serve where web/js opens a WebSocket, and sandbox -> reader where
  src/sandbox/ starts the volvis-reader program.

Writes docs/architecture.dot (deterministic: sorted, one arrow per pair of
nodes, no counts, so it changes only when an arrow appears or goes) and,
with --svg and Graphviz's `dot` installed, docs/architecture.svg. --check
writes nothing and exits 1 when docs/architecture.dot differs from what the
tree gives (the CTest test_tree_architecture_graph). Every run fails (exit 1)
on an import circle between folders of src/ (a strongly connected set of
two or more folders), which it names; --cycles prints the circles only.
"""
import argparse
import importlib.util
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def load_layer_map():
    spec = importlib.util.spec_from_file_location("check_includes",
                                                  os.path.join(HERE, "check-includes.py"))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


CI = load_layer_map()
LAYERS, PUBLIC = CI.LAYERS, CI.PUBLIC

# The front ends: node -> (folder, label)
FRONT = {
    "cli": ("apps/volvis", "volvis (CLI)\\napps/volvis"),
    "serve": ("apps/volvis/serve", "volvis serve\\napps/volvis/serve"),
    "gui": ("apps/volvis-gui", "volvis-gui (GTK 4)\\napps/volvis-gui"),
    "reader": ("apps/volvis-reader", "volvis-reader\\n(sandboxed reader process)"),
    "python": ("python", "Python package (cffi)\\npython/volvis"),
    "web": ("web", "browser client\\nweb/"),
}
UMBRELLA = "include/volvis/volvis.h"
NAME_RE = re.compile(r"\b(?:vv_|VV_|Vv(?!g[A-Z0-9]))\w+")


def strip_c_comments(text):
    return re.sub(r"/\*.*?\*/|//[^\n]*", " ", text, flags=re.S)


def node_of(rel):
    """The node of a repository-relative file, or None."""
    parts = rel.split("/")
    if parts[0] == "src" and len(parts) >= 3:
        return parts[1]
    if parts[0] == "include" and len(parts) >= 3 and parts[1] == "volvis":
        return PUBLIC.get("/".join(parts[2:]))  # "apps" for the umbrella
    if rel.startswith("apps/volvis/serve/"):
        return "serve"
    for node, (folder, _) in FRONT.items():
        if rel.startswith(folder + "/"):
            return node
    return None


def files_under(root, top, exts):
    out = []
    for d, dirs, names in os.walk(os.path.join(root, top)):
        dirs[:] = sorted(x for x in dirs if x not in ("__pycache__", "node_modules"))
        for n in names:
            if n.endswith(exts):
                out.append(os.path.relpath(os.path.join(d, n), root).replace(os.sep, "/"))
    return sorted(out)


def declared_names(root):
    """{name: component} for the vv_/Vv/VV_ names each public header declares:
    its macros, typedefs, struct and enum tags, enum values and function
    prototypes at file scope (not names it only uses)."""
    owner = {}
    for rel in files_under(root, "include/volvis", (".h",)):
        if rel == UMBRELLA:
            continue
        comp = PUBLIC.get(rel[len("include/volvis/"):])
        text = strip_c_comments(open(os.path.join(root, rel), encoding="utf-8").read())
        text = text.replace("\\\n", " ")
        names = set(re.findall(r"^[ \t]*#[ \t]*define[ \t]+(\w+)", text, re.M))
        code = re.sub(r"^[ \t]*#.*$", " ", text, flags=re.M)
        code = re.sub(r'extern\s*"C"\s*\{', " ", code)  # its closing brace: depth clamps at 0
        # file scope only: function bodies (static inline helpers) use names
        depth, kept = 0, []
        for ch in code:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth = max(0, depth - 1)
            if depth == 0:
                kept.append(ch)
        top = "".join(kept)
        names.update(re.findall(r"\b(?:struct|enum|union)\s+(\w+)", code))
        names.update(re.findall(r"}\s*(\w+)\s*;", code))  # typedef struct {...} name;
        names.update(re.findall(r"\btypedef\b[^;{]*?\b(\w+)\s*;", top))
        names.update(re.findall(r"\(\s*\*\s*(\w+)\s*\)\s*\(", top))  # function pointer types
        names.update(re.findall(r"[\w\*]\s+\**\s*(\w+)\s*\(", top))  # prototypes
        for body in re.findall(r"\benum\b[^{;]*\{([^}]*)\}", code):
            names.update(re.findall(r"(\w+)\s*(?:=[^,]*)?(?:,|$)", body.strip()))
        for n in names:
            if NAME_RE.fullmatch(n) and n not in owner:
                owner[n] = comp
    return owner


def names_used(root, rel):
    text = open(os.path.join(root, rel), encoding="utf-8", errors="replace").read()
    if rel.endswith(".py"):
        used = set(re.findall(r"\blib\.((?:vv_|VV_)\w+)", text))
        for s in re.findall(r"ffi\.\w+\(\s*[\"']([^\"']+)[\"']", text):
            used.update(NAME_RE.findall(s))
        return used
    return set(NAME_RE.findall(strip_c_comments(text)))


def collect(root):
    """(nodes, include arrows, other arrows {(a, b): label})."""
    for d in sorted(os.listdir(os.path.join(root, "src"))):
        if os.path.isdir(os.path.join(root, "src", d)) and d not in LAYERS:
            raise SystemExit("architecture-graph: src/%s is not in the layer map "
                             "(LAYERS of scripts/check-includes.py)" % d)
    comps = sorted(c for c in LAYERS if c not in ("apps", "python")
                   and os.path.isdir(os.path.join(root, "src", c)))
    owner = declared_names(root)
    arrows = set()
    by_use = {}  # front end -> files resolved by the names they use
    c_files = []
    for top in ("src", "include/volvis", "apps", "python"):
        c_files += files_under(root, top, CI.SOURCE_EXT)
    for rel in c_files:
        me = node_of(rel)
        if me is None or me == "apps":  # the umbrella header itself
            continue
        text = open(os.path.join(root, rel), encoding="utf-8", errors="replace").read()
        for m in CI.INCLUDE_RE.finditer(text):
            target = CI.resolve(root, rel, m.group(1) or m.group(2))
            if target is None:
                continue
            if target == UMBRELLA:
                by_use.setdefault(me, []).append(rel)
                continue
            them = node_of(target)
            if them and them != me and them != "apps":
                arrows.add((me, them))
    # a front end sees the public API only (check-includes.py): all its files
    # are resolved by the names they use, whether they include the umbrella
    # header directly or through a header of their own (apps/volvis/cli.h)
    for rel in c_files + files_under(root, "python", (".py",)):
        if node_of(rel) in FRONT:
            by_use.setdefault(node_of(rel), []).append(rel)
    for me, rels in by_use.items():
        for rel in sorted(set(rels)):
            for n in names_used(root, rel):
                them = owner.get(n)
                if them and them != me:
                    arrows.add((me, them))
    other = {}
    if any("new WebSocket(" in open(os.path.join(root, f), encoding="utf-8").read()
           for f in files_under(root, "web", (".js",))):
        other[("web", "serve")] = "WebSocket"
    if any('"volvis-reader"' in open(os.path.join(root, f), encoding="utf-8").read()
           for f in files_under(root, "src/sandbox", (".c",))):
        other[("sandbox", "reader")] = "starts"
    return comps, arrows, other


def cycles(comps, arrows):
    """Strongly connected sets of two or more folders of src/ (Tarjan)."""
    graph = {c: sorted(b for a, b in arrows if a == c and b in comps) for c in comps}
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                out.append(sorted(scc))

    for c in comps:
        if c not in index:
            visit(c)
    return sorted(out)


def dot_text(comps, arrows, other):
    top = max(LAYERS[c] for c in comps)
    layer = dict((c, LAYERS[c]) for c in comps)
    layer.update({"cli": top + 1, "serve": top + 1, "gui": top + 1, "python": top + 1,
                  "reader": top + 1, "web": top + 2})
    lines = [
        "// Generated by scripts/architecture-graph.py from the #includes of src/,",
        "// include/volvis/, apps/ and python/; do not edit (test_tree_architecture_graph",
        "// fails when it differs from the tree). Solid: includes (or, for front ends",
        "// on the umbrella header and Python's cffi, the headers of the names used);",
        "// dashed: a process or protocol, not an include. Layers: scripts/check-includes.py.",
        "digraph volvis {",
        '  graph [rankdir=TB, nodesep=0.25, ranksep=0.55, fontname="Helvetica", '
        'fontsize=11, newrank=true];',
        '  node [shape=box, style="rounded,filled", fontname="Helvetica", fontsize=11, '
        'fillcolor="#eef3fb", color="#5b7db1"];',
        '  edge [color="#6b7785", arrowsize=0.6];',
    ]
    for node in sorted(FRONT):
        lines.append('  "%s" [label="%s", fillcolor="#fdf1dc", color="#b5832b"];'
                     % (node, FRONT[node][1]))
    for c in comps:
        lines.append('  "%s" [label="%s\\nsrc/%s"];' % (c, c, c))
    for lv in sorted(set(layer.values()), reverse=True):
        members = sorted(n for n, v in layer.items() if v == lv)
        lines.append("  { rank=same; %s }" % " ".join('"%s";' % n for n in members))
    # everything stands on core: those arrows faint; a front end's arrows in its colour
    for a, b in sorted(arrows):
        style = (' [color="#c8ced6"]' if b == "core" else
                 ' [color="#d8b27a"]' if a in FRONT else "")
        lines.append('  "%s" -> "%s"%s;' % (a, b, style))
    for (a, b), label in sorted(other.items()):
        # the reader is started from below; the web client sits above serve
        lines.append('  "%s" -> "%s" [style=dashed, label="%s", fontsize=9, '
                     'fontname="Helvetica"%s];' % (a, b, label,
                                                    "" if a in FRONT else ", constraint=false"))
    lines.append("}")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--root", default=os.path.join(HERE, ".."))
    ap.add_argument("--check", action="store_true",
                    help="compare with docs/architecture.dot, write nothing")
    ap.add_argument("--svg", action="store_true", help="also write docs/architecture.svg (dot)")
    ap.add_argument("--cycles", action="store_true", help="print the import circles only")
    a = ap.parse_args()
    root = os.path.abspath(a.root)
    comps, arrows, other = collect(root)
    circles = cycles(comps, arrows)
    for c in circles:
        inner = sorted((x, y) for x, y in arrows if x in c and y in c)
        print("import circle between folders of src/: %s (%s)" % (
            ", ".join(c), "; ".join("%s -> %s" % e for e in inner)))
    if a.cycles:
        return 1 if circles else 0
    text = dot_text(comps, arrows, other)
    path = os.path.join(root, "docs", "architecture.dot")
    if a.check:
        old = open(path, encoding="utf-8").read() if os.path.exists(path) else ""
        if old != text:
            import difflib
            sys.stdout.writelines(difflib.unified_diff(
                old.splitlines(True), text.splitlines(True), "docs/architecture.dot (committed)",
                "docs/architecture.dot (the tree)"))
            print("architecture-graph: docs/architecture.dot is out of date: run "
                  "scripts/architecture-graph.py --svg and commit both files")
            return 1
        print("architecture-graph: docs/architecture.dot matches the tree "
              "(%d nodes, %d arrows)" % (len(comps) + len(FRONT), len(arrows) + len(other)))
        return 1 if circles else 0
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    print("wrote %s (%d nodes, %d arrows)" % (path, len(comps) + len(FRONT),
                                              len(arrows) + len(other)))
    if a.svg:
        try:
            svg = subprocess.run(["dot", "-Tsvg", path], capture_output=True, check=True).stdout
        except FileNotFoundError:
            print("dot (Debian package graphviz) is not installed: no SVG written")
            return 1
        with open(os.path.join(root, "docs", "architecture.svg"), "wb") as f:
            f.write(svg)
        print("wrote %s" % os.path.join(root, "docs", "architecture.svg"))
    return 1 if circles else 0


if __name__ == "__main__":
    sys.exit(main())

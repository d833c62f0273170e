#!/usr/bin/env python3
"""Lists the imports between the top-level modules of host/src (crate `rigctl`) and fails on a
cycle, and checks that the host module table of docs/ARCHITECTURE.md ("Host library modules")
names exactly the modules of the tree.

    python3 scripts/module_graph.py            # print the graph, exit 1 on a cycle or mismatch
    python3 scripts/module_graph.py --dot      # the graph in Graphviz dot

An import is any `crate::NAME` path in a module's files (use statements and qualified paths),
outside comments; `super::` stays inside the module. `cli` (the binary's commands) may use every
module and is left out of the cycle check, as are `lib.rs` and `main.rs`.

Inside the folders of STRICT_FOLDERS the files (and sub-folders) must not import each other in a
circle either (`super::NAME`, `crate::FOLDER::NAME`); the circles of the other folders are
listed, not failed.
"""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SRC = ROOT / "host" / "src"
IGNORED = {"cli"}
# Edges the layering forbids (docs/ARCHITECTURE.md "Layering"): the identification does not
# depend on the fusion, and nothing that diagnoses, compensates or plans depends on the
# simulator.
FORBIDDEN = {("calib", "fusion"), ("diagnose", "sim"), ("compensate", "sim"), ("plan", "sim"), ("model", "sim"), ("calib", "sim")}


def modules():
    mods = {}
    for p in sorted(SRC.iterdir()):
        if p.is_dir():
            mods[p.name] = sorted(p.rglob("*.rs"))
        elif p.suffix == ".rs" and p.stem not in ("lib", "main"):
            mods[p.stem] = [p]
    return mods


def strip_comments(text):
    """The code of a file without comments and without its unit-test module (`#[cfg(test)] mod
    tests { ... }`, at the end of a file by convention): tests may use anything."""
    test_mod = re.search(r"^#\[cfg\(test\)\]\s*\n\s*mod tests\b", text, flags=re.M)
    if test_mod:
        text = text[: test_mod.start()]
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return "\n".join(line.split("//", 1)[0] for line in text.splitlines())


def graph(mods):
    edges = {m: {} for m in mods}
    for m, files in mods.items():
        for f in files:
            body = strip_comments(f.read_text(encoding="utf-8"))
            # crate::x paths, and the brace form `use crate::{a::..., b::...}`
            targets = set(re.findall(r"\bcrate::([a-z_][a-z0-9_]*)", body))
            for group in re.findall(r"\bcrate::\{([^}]*)\}", body, flags=re.S):
                targets |= set(re.findall(r"(?:^|[,{\s])([a-z_][a-z0-9_]*)\s*(?:::|,|$)", group))
            for t in targets:
                if t in mods and t != m:
                    edges[m].setdefault(t, set()).add(f.relative_to(SRC).as_posix())
    return edges


# Folders whose files may not import each other in a circle.
STRICT_FOLDERS = ("calib", "diagnose")


def folder_graph(folder):
    """Imports between the files and sub-folders of `folder` (code only, unit tests left out)."""
    parts = {}
    for p in sorted(folder.iterdir()):
        if p.is_dir():
            parts[p.name] = sorted(q for q in p.rglob("*.rs") if q.name != "tests.rs")
        elif p.suffix == ".rs" and p.stem != "mod":
            parts[p.stem] = [p]
    edges = {m: set() for m in parts}
    for m, files in parts.items():
        body = "\n".join(strip_comments(f.read_text(encoding="utf-8")) for f in files)
        body = body.replace("super::super::", "super::")
        for t in parts:
            if t == m:
                continue
            here = rf"\bsuper::{t}\b|\bcrate::{folder.name}::{t}\b"
            group = rf"\bsuper::\{{[^}}]*\b{t}\b"
            if re.search(here, body) or re.search(group, body, flags=re.S):
                edges[m].add(t)
    return edges


def folder_cycles():
    """(folder, circle) for every import circle inside a folder of host/src."""
    out = []
    for p in sorted(SRC.iterdir()):
        if p.is_dir():
            out += [(p.name, c) for c in cycles(folder_graph(p))]
    return out


def cycles(edges):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in edges:
        if v not in index:
            visit(v)
    return out


TABLE_DOC = ROOT / "docs" / "ARCHITECTURE.md"


def table_modules():
    text = TABLE_DOC.read_text(encoding="utf-8")
    start = text.find("Host library modules")
    if start < 0:
        return None
    names = set()
    for line in text[start:].splitlines()[1:]:
        if line.startswith("|"):
            cell = line.split("|")[1]
            names |= set(re.findall(r"`([a-z_][a-z0-9_]*)/?`", cell))
        elif names:
            break
    return names


def documented_graph():
    """The graph block after "The current graph:" in docs/ARCHITECTURE.md (lines `m -> a, b`)."""
    text = TABLE_DOC.read_text(encoding="utf-8")
    m = re.search(r"The current graph:\s*```\n(.*?)```", text, flags=re.S)
    return None if m is None else [l.rstrip() for l in m.group(1).splitlines() if l.strip()]


def main():
    mods = modules()
    edges = graph(mods)
    checked = {m: {t: f for t, f in e.items() if t not in IGNORED} for m, e in edges.items() if m not in IGNORED}
    if "--dot" in sys.argv:
        print("digraph rigctl {")
        for m, e in sorted(checked.items()):
            for t in sorted(e):
                print(f'  "{m}" -> "{t}";')
        print("}")
        return 0
    lines = [f"{m:10} -> {', '.join(sorted(e)) or '(nothing)'}" for m, e in sorted(checked.items())]
    print("\n".join(lines))
    bad = 0
    for a, b in sorted(FORBIDDEN):
        if b in checked.get(a, {}):
            bad = 1
            print(f"\nforbidden edge {a} -> {b}: {', '.join(sorted(checked[a][b]))}")
    doc = documented_graph()
    wanted = [l for l in lines if not l.endswith("(nothing)")]
    if doc != wanted:
        bad = 1
        print("\nthe graph in docs/ARCHITECTURE.md (after 'The current graph:') differs; it should read:")
        print("\n".join(wanted))
    for comp in cycles(checked):
        bad = 1
        print(f"\nCYCLE between {', '.join(comp)}:")
        for m in comp:
            for t in comp:
                if t in checked[m]:
                    print(f"  {m} -> {t}: {', '.join(sorted(checked[m][t]))}")
    for folder, comp in folder_cycles():
        strict = folder in STRICT_FOLDERS
        bad |= int(strict)
        print(f"\n{'CYCLE' if strict else 'circle (listed, not failed)'} inside {folder}/: {', '.join(comp)}")
    listed = table_modules()
    tree = set(mods) - IGNORED
    if listed is None:
        print("\ndocs/ARCHITECTURE.md has no 'Host library modules' table")
        bad = 1
    elif listed != tree:
        bad = 1
        if tree - listed:
            print(f"\nthe module table (docs/ARCHITECTURE.md) lacks: {', '.join(sorted(tree - listed))}")
        if listed - tree:
            print(f"\nthe module table (docs/ARCHITECTURE.md) names modules not in host/src: {', '.join(sorted(listed - tree))}")
    if not bad:
        print(f"\nno import cycle between host/src modules nor inside {', '.join(f + '/' for f in STRICT_FOLDERS)}; the module table and the graph of docs/ARCHITECTURE.md match the tree")
    return bad


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""The import graph of the library in src/: every `crate::…` and `super::…` path between files.

Prints the strongly connected components that span more than one folder and the imports that run up a
layer (LAYERS below, bottom first). Used for issue 33 ("the engine contract at the bottom"); run from the
repository root: `python3 scripts/imports.py [--edges]`.
"""
import os
import re
import sys

# Bottom first. A folder may import its own layer or the ones below. io/ is meant to hold file formats only
# (tables, JSON, the VTK writer, positions, the checkpoint envelope), below the engine contract.
LAYERS = [
    ["lib", "error", "clock", "geometry", "team", "io"],
    ["engine"],
    ["plane"],
    ["nscd", "md"],
    ["run"],
    ["settlement"],
    ["scene"],
    ["report"],
    ["open"],
    ["scenarios"],
    ["studies"],
]
LAYER = {name: i for i, names in enumerate(LAYERS) for name in names}


def module_files(root="src"):
    """Module path (tuple) -> file."""
    mods = {}
    for dirpath, _, files in os.walk(root):
        for f in files:
            if not f.endswith(".rs"):
                continue
            path = os.path.join(dirpath, f)
            # The binary (main.rs, cli/) is its own crate on top of the library.
            if path == os.path.join(root, "main.rs") or os.path.join(root, "cli") in path:
                continue
            rel = os.path.relpath(path, root)[:-3].split(os.sep)
            if rel[-1] == "mod":
                rel = rel[:-1]
            if rel == ["lib"]:
                rel = []
            mods[tuple(rel)] = path
    return mods


def strip_comments(text):
    text = re.sub(r"//[^\n]*", "", text)
    return re.sub(r"/\*.*?\*/", "", text, flags=re.S)


def expand(tree):
    """Expand a use tree `a::{b, c::{d}}` into paths."""
    tree = tree.strip()
    depth = 0
    for i, ch in enumerate(tree):
        if ch == "{":
            if depth == 0:
                prefix = tree[:i]
                inner = tree[i + 1 : tree.rindex("}")]
                parts, d, start = [], 0, 0
                for j, c in enumerate(inner):
                    if c == "{":
                        d += 1
                    elif c == "}":
                        d -= 1
                    elif c == "," and d == 0:
                        parts.append(inner[start:j])
                        start = j + 1
                parts.append(inner[start:])
                out = []
                for p in parts:
                    if p.strip():
                        out += [prefix + q for q in expand(p)]
                return out
            depth += 1
    return [tree]


def resolve(path, here, mods):
    """The file a path names (longest module prefix), or None."""
    parts = [p.strip() for p in path.split("::") if p.strip()]
    parts = [p.split(" as ")[0].strip() for p in parts]
    if not parts:
        return None
    if parts[0] == "crate":
        base, rest = [], parts[1:]
    elif parts[0] in ("super", "self"):
        base = list(here)
        # a file's module is `here`; `super` is its parent
        rest = parts
        while rest and rest[0] in ("super", "self"):
            if rest[0] == "super":
                base = base[:-1]
            rest = rest[1:]
    else:
        return None
    best = None
    for k in range(len(rest) + 1):
        key = tuple(base + rest[:k])
        if key in mods:
            best = mods[key]
    return best


def graph(root="src"):
    mods = module_files(root)
    files = {v: k for k, v in mods.items()}
    edges = {}
    for path, here in files.items():
        text = strip_comments(open(path).read())
        targets = set()
        for m in re.finditer(r"\buse\s+((?:crate|super|self)::[^;]*);", text, flags=re.S):
            for p in expand(m.group(1)):
                t = resolve(p, here, mods)
                if t:
                    targets.add(t)
        for m in re.finditer(r"(?<![:\w])((?:crate|super)(?:::\w+)+)", text):
            t = resolve(m.group(1), here, mods)
            if t:
                targets.add(t)
        targets.discard(path)
        edges[path] = targets
    return edges


def folder(path):
    rel = os.path.relpath(path, "src").split(os.sep)
    return rel[0][:-3] if len(rel) == 1 else rel[0]


def sccs(edges):
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]
    sys.setrecursionlimit(10000)

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
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
            out.append(comp)

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def main():
    edges = graph()
    bad = [c for c in sccs(edges) if len({folder(f) for f in c}) > 1]
    print(f"circles spanning folders: {len(bad)}")
    for c in bad:
        print(f"  {len(c)} files in {sorted({folder(f) for f in c})}")
        if "--edges" in sys.argv:
            for f in sorted(c):
                print("    " + f)
    up = []
    for a, ts in sorted(edges.items()):
        for b in sorted(ts):
            fa, fb = folder(a), folder(b)
            if fa != fb and LAYER.get(fb, -1) > LAYER.get(fa, -1):
                up.append((a, b))
    print(f"imports up a layer: {len(up)}")
    for a, b in up:
        print(f"  {a} -> {b}")


if __name__ == "__main__":
    main()

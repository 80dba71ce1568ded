#!/usr/bin/env bash
# The house's dependency rules (issue 15), checked on the tree as it is:
#   1. Crate graph (from `cargo metadata`): no package but fcc_bridge itself depends on the
#      bridge application (fcc_bridge); fcc_mission's workspace dependencies are fcc_msgs (the
#      link vocabulary and WGS-84 geodesy for lat/lon goals) and the ROS library fcc_ros only; fcc_ros depends on fcc_msgs and fcc_nav (the one f64 angle wrap) only; fcc_msgs on
#      no workspace crate.
#   2. The MCU crate's default build (`cargo build -p fcc_firmware`) pulls in no simulator
#      dependency.
#   3. No import circles between the modules of fcc_bridge and of fcc_ros: each source file is a
#      module; `crate::a::b` and `super::x` paths in code (comments left out) are its edges.
# Prints one PASS/FAIL line per rule; exits 1 on any FAIL.
#   usage: scripts/check-deps.sh
set -euo pipefail
cd "$(dirname "$0")/.."

meta=$(mktemp)
tree=$(mktemp)
trap 'rm -f "$meta" "$tree"' EXIT
cargo metadata --offline --locked --no-deps --format-version 1 > "$meta"
# The MCU crate's default build, normal dependencies only (not its dev/build dependencies).
cargo tree --offline --locked -p fcc_firmware -e normal --prefix none --format '{p}' > "$tree"

python3 - "$meta" "$tree" <<'EOF'
import json, os, re, sys

meta = json.load(open(sys.argv[1]))
tree = open(sys.argv[2]).read().split()
pkgs = {p["name"]: p for p in meta["packages"]}
ok = True

def report(passed, rule, detail=""):
    global ok
    ok &= passed
    print(("PASS " if passed else "FAIL ") + rule + (f": {detail}" if detail else ""))

def ws_deps(name):
    """Workspace packages `name` depends on (any kind: normal, dev, build; optional too)."""
    return sorted({d["name"] for d in pkgs[name]["dependencies"] if d["name"] in pkgs})

# 1. Crate graph.
users = [n for n in pkgs if n != "fcc_bridge" and "fcc_bridge" in ws_deps(n)]
report(not users, "no crate but fcc_bridge's own targets depends on fcc_bridge",
       f"{users} do" if users else "")
for name, allowed in [("fcc_mission", {"fcc_msgs", "fcc_ros"}), ("fcc_ros", {"fcc_msgs", "fcc_nav"}),
                      ("fcc_msgs", set())]:
    if name not in pkgs:
        report(False, f"{name} exists")
        continue
    extra = sorted(set(ws_deps(name)) - allowed)
    what = f"{', '.join(sorted(allowed))} only" if allowed else "no workspace crate"
    report(not extra, f"{name} depends on {what}",
           f"also on {extra}" if extra else "")

# 2. fcc_firmware's default build has no simulator dependency.
sim = {"fcc_sim", "fcc_mission", "serde_yaml", "serde_norway", "serde_path_to_error", "rand",
       "rand_chacha", "rand_distr", "clap", "nix", "signal-hook"}
found = sorted({t for t in tree if t in sim})
report(not found, "cargo build -p fcc_firmware pulls in no simulator dependency",
       f"it pulls {found}" if found else "")

# 3. Module import circles.
def modules(src):
    """{module path: file} for every .rs file under src (lib.rs = the root, "")."""
    out = {}
    for dirpath, _, files in os.walk(src):
        if os.path.relpath(dirpath, src).split(os.sep)[0] == "bin":
            continue  # binaries are crates of their own
        for f in files:
            if not f.endswith(".rs"):
                continue
            rel = os.path.relpath(os.path.join(dirpath, f), src)[:-3].split(os.sep)
            if rel in (["lib"], ["main"]):
                continue
            if rel[-1] == "mod":
                rel = rel[:-1]
            out["::".join(rel)] = os.path.join(dirpath, f)
    return out

def code(text):
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'"(\\.|[^"\\])*"', '""', text)
    return "\n".join(l.split("//")[0] for l in text.splitlines())

def paths(text):
    """Paths after crate:: / super:: (brace groups expanded one level), as segment lists."""
    out = []
    for m in re.finditer(r"\b(crate|super)::((?:\w+::)*)(\{[^}]*\}|\w+)", text):
        head = (m.group(1) + "::" + m.group(2)).rstrip(":").split("::")
        tail = m.group(3)
        items = [t.strip() for t in tail[1:-1].split(",")] if tail.startswith("{") else [tail]
        for it in items:
            if it:
                out.append(head + [s for s in it.split("::") if s and s != "self"])
    return out

def resolve(mod, path, mods):
    """The module a path names: its longest prefix that is a module file (None: the root)."""
    if path[0] == "crate":
        base, rest = [], path[1:]
    else:  # super: relative to the module's parent (a file module's parent is its directory)
        base, rest = (mod.split("::")[:-1] if mod else []), path[1:]
    full = base + rest
    for n in range(len(full), 0, -1):
        cand = "::".join(full[:n])
        if cand in mods:
            return cand
    return None

def cycles(graph):
    """Strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on, out, i = {}, {}, [], set(), [], [0]
    def visit(v):
        index[v] = low[v] = i[0]; i[0] += 1; stack.append(v); on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w); low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop(); on.discard(w); comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))
    for v in graph:
        if v not in index:
            visit(v)
    return out

for crate, src in [("fcc_bridge", "fcc_bridge/src"), ("fcc_ros", "fcc_bridge/ros/src")]:
    mods = modules(src)
    graph = {m: set() for m in mods}
    for m, f in mods.items():
        for p in paths(code(open(f).read())):
            t = resolve(m, p, mods)
            # A module's own children (its tests, its parts) and itself are not imports.
            if t and t != m and not t.startswith(m + "::") and not (m and m.startswith(t + "::")):
                graph[m].add(t)
    circ = cycles(graph)
    report(not circ, f"{crate}: no import circles between its {len(mods)} modules",
           "; ".join(" <-> ".join(c) for c in circ))

sys.exit(0 if ok else 1)
EOF

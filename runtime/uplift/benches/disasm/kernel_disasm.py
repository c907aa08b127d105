#!/usr/bin/env python3
"""Per-kernel instruction counts of the shipped CPU kernels, read from a disassembly.

Builds `runtime/kernels/examples/kernel_symbols.rs` in release with v0 symbol mangling (into
target/disasm, with the LLVM options of .cargo/config.toml), so that every monomorphised and
outlined function of a packet kernel names its module and SIMD level, disassembles it with
objdump and, for each kernel given, prints the static counts of its code per SIMD level:
instructions, gathers, divisions, square roots, reciprocal (square-root) estimates, float<->int
conversions, fused multiply-adds, stack accesses (spills and reloads), and the same per lane
(a packet of 16 lanes on AVX-512, 8 on AVX2). The scalar writer's kernels are counted per
multiversion function, totals only: each holds LLVM's vector loop together with its scalar
remainder and fallbacks, so the table gives the width most of its float arithmetic runs at.

Static counts are what one pass over the code holds, not what a run executes: branches skipped
for a whole packet (guarded calls, masked ifs no lane takes) are counted too.

`--functions` adds, per packet level, one row per function (its role read from the name: the
split kernel's group pass, outlined once per packet of groups; the grouped batch loop with the
point pass inlined; the unsplit batch loop; an outlined lobe), so that a split kernel's cost per
point is the point pass's row plus the group pass's divided by the points per group.

Usage: python3 runtime/uplift/benches/disasm/kernel_disasm.py [--no-build | --binary PATH] [--functions] KERNEL...
       (KERNEL: a shipped kernel module, e.g. bsdf_conductor_eval uplift_stack_eval)
"""
import os
import re
import subprocess
import sys
from collections import defaultdict

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", ".."))
TARGET = os.path.join(ROOT, "target", "disasm")
BINARY = os.path.join(TARGET, "release", "examples", "kernel_symbols")

CLASSES = {
    "gathers": re.compile(r"^v(p)?gather"),
    "divisions": re.compile(r"^v?div[ps][sd]"),
    "square roots": re.compile(r"^v?sqrt[ps][sd]"),
    "rcp/rsqrt": re.compile(r"^v?(rcp|rsqrt)(14|28)?[ps][sd]"),
    "conversions": re.compile(r"^v?cvt"),
    "FMAs": re.compile(r"^vf(n)?m(add|sub)"),
}


def build():
    flags = "-C symbol-mangling-version=v0 -Cllvm-args=-unroll-threshold=6000 -Cllvm-args=-alias-set-saturation-threshold=10000"
    env = dict(os.environ, CARGO_TARGET_DIR=TARGET, RUSTFLAGS=flags)
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "uplift_kernels", "--example", "kernel_symbols"], cwd=ROOT, env=env, check=True)


def functions():
    """(demangled name, [mnemonic, operands]) for every function of the binary."""
    out = subprocess.run(["objdump", "-d", "--no-show-raw-insn", "-C", BINARY], capture_output=True, text=True, check=True).stdout
    funcs = []
    name, body = None, []
    for line in out.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", line)
        if m:
            if name is not None:
                funcs.append((name, body))
            name, body = m.group(1), []
            continue
        m = re.match(r"^\s+[0-9a-f]+:\s+(\S+)\s*(.*)$", line)
        if m and name is not None:
            body.append((m.group(1), m.group(2)))
    if name is not None:
        funcs.append((name, body))
    return funcs


def level_of(name):
    if "Avx512" in name or "avx512::entry" in name:
        return "AVX-512 packet", 16
    if "Avx2" in name or "avx2::entry" in name:
        return "AVX2 packet", 8
    m = re.search(r"batch_(\w+?)_version", name)
    if m:
        feats = m.group(1)
        if "avx512f" in feats:
            return "scalar writer, avx512 version", 16
        if "avx2" in feats:
            return "scalar writer, avx2 version", 8
        return "scalar writer, " + ("sse4 version" if "sse41" in feats else "default version"), 4
    return None, None


FLOAT_OP = re.compile(r"^v?(add|sub|mul|div|sqrt|min|max)(ps|ss)$")


def float_width(body):
    """The lanes the function's float arithmetic runs at: the most frequent of scalar (ss: 1)
    and packed on xmm (4), ymm (8) or zmm (16) registers. The scalar writer's batch loop is
    vectorised across points by LLVM or not at all."""
    votes = defaultdict(int)
    for mnemonic, operands in body:
        m = FLOAT_OP.match(mnemonic)
        if not m:
            continue
        if m.group(2) == "ss":
            votes[1] += 1
        else:
            votes[16 if "%zmm" in operands else 8 if "%ymm" in operands else 4] += 1
    return max(votes, key=votes.get) if votes else 1


def count(kernel, funcs):
    packet_module = f"{kernel}_packet"
    scalar_static = kernel.upper() + "_SCALAR"
    rows = defaultdict(lambda: defaultdict(int))
    lanes = {}
    for name, body in funcs:
        if packet_module not in name and scalar_static not in name and f"generated::{kernel}::" not in name:
            continue
        level, width = level_of(name)
        if level is None:
            continue
        if level.startswith("scalar writer"):
            width = float_width(body)
        lanes[level] = width
        r = rows[level]
        r["functions"] += 1
        for mnemonic, operands in body:
            r["instructions"] += 1
            for cls, rx in CLASSES.items():
                if rx.match(mnemonic):
                    r[cls] += 1
            if "(%rsp)" in operands or "(%rbp)" in operands:
                r["stack accesses"] += 1
    return rows, lanes


def role(name):
    """What a packet kernel's function is, from its demangled name."""
    if "outline" in name and re.search(r"_g\d+<", name):
        return "group pass: outlined callee"
    if "grouped_packets" in name and "outline" in name:
        return "group pass"
    if "grouped" in name:
        return "grouped batch loop + point pass"
    if "outline" in name:
        return "unsplit kernel: outlined callee"
    return "unsplit batch loop"


def function_rows(kernel, funcs, level_name):
    packet_module = f"{kernel}_packet"
    out = []
    for name, body in funcs:
        if packet_module not in name:
            continue
        level, width = level_of(name)
        if level != level_name:
            continue
        r = defaultdict(int)
        for mnemonic, operands in body:
            r["instructions"] += 1
            for cls, rx in CLASSES.items():
                if rx.match(mnemonic):
                    r[cls] += 1
            if "(%rsp)" in operands or "(%rbp)" in operands:
                r["stack accesses"] += 1
        out.append((role(name), width, r))
    return out


def main():
    global BINARY
    argv = sys.argv[1:]
    if "--binary" in argv:
        # Another build of the example (an older commit's, say), disassembled as it is.
        i = argv.index("--binary")
        BINARY = os.path.abspath(argv[i + 1])
        argv = argv[:i] + ["--no-build"] + argv[i + 2:]
    args = [a for a in argv if not a.startswith("--")]
    if "--no-build" not in argv:
        build()
    if not args:
        args = ["bsdf_conductor_eval", "uplift_stack_eval"]
    funcs = functions()
    cols = ["instructions"] + list(CLASSES) + ["stack accesses"]
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    print(f"# static instruction counts of shipped kernels ({cpu}; binary {os.path.relpath(BINARY, ROOT)})")
    for kernel in args:
        rows, lanes = count(kernel, funcs)
        if not rows:
            print(f"\n{kernel}: no functions found (is it shipped?)")
            continue
        print(f"\n## {kernel}\n")
        print("| code | functions | lanes | " + " | ".join(cols) + " |")
        print("|---|---|---|" + "---|" * len(cols))
        for level in sorted(rows):
            r = rows[level]
            w = lanes[level]
            if level.startswith("scalar writer"):
                # One function holds LLVM's vector loop, its scalar remainder and fallbacks:
                # totals only, with the width most of its float arithmetic runs at.
                cells = [str(r[c]) for c in cols]
                print(f"| {level} | {r['functions']} | mostly {w} | " + " | ".join(cells) + " |")
            else:
                cells = [f"{r[c]} ({r[c] / w:.1f}/lane)" for c in cols]
                print(f"| {level} | {r['functions']} | {w} | " + " | ".join(cells) + " |")
        if "--functions" in argv:
            for level in sorted(l for l in rows if not l.startswith("scalar writer")):
                print(f"\n{kernel}, {level}, per function:\n")
                print("| function | " + " | ".join(cols) + " |")
                print("|---|" + "---|" * len(cols))
                frows = function_rows(kernel, funcs, level)
                for rl, w, r in sorted(frows, key=lambda x: -x[2]["instructions"]):
                    print(f"| {rl} | " + " | ".join(f"{r[c]} ({r[c] / w:.1f}/lane)" for c in cols) + " |")
                point = [r for rl, _, r in frows if rl.startswith("grouped batch loop")]
                group = [r for rl, _, r in frows if rl.startswith("group pass")]
                if point:
                    w = lanes[level]
                    per = {c: sum(r[c] for r in point) / w + sum(r[c] for r in group) / (w * 16) for c in cols}
                    print("| **split, per point at 16 points per group** (point pass per lane + group pass / (lanes · 16)) | " + " | ".join(f"{per[c]:.1f}" for c in cols) + " |")


if __name__ == "__main__":
    main()

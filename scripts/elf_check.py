#!/usr/bin/env python3
"""Call-graph check of a Cortex-M ELF: from each root symbol, follow every
direct call and tail call (bl, b, b.w to another function) in the
disassembly, and fail when a forbidden routine is reachable: double-precision
soft float (__aeabi_d*, __aeabi_f2d, libgcc/compiler-builtins *df* routines)
or a panic (core::panicking, rust_begin_unwind, panic handlers). Indirect
calls (blx/bx to a register other than lr) cannot be followed: they fail too.
With --no-double, the whole image must also contain no double-precision
routine at all (reachable from anywhere).

usage: elf_check.py [--no-double] OBJDUMP ELF ROOT [ROOT...]   (roots optional with --no-double)
exit 0 clean, 1 violation (with the call chain), 2 usage/tool error.
"""
import re
import subprocess
import sys

FORBIDDEN = re.compile(
    r"^(__aeabi_d\w*|__aeabi_[lu]?[il]?2d|__aeabi_f2d|__\w*df[23]\w*|__\w*df\w*|"
    r".*panicking.*|rust_begin_unwind|.*panic_fmt.*|.*panic_bounds_check.*|"
    r".*unwrap_failed.*|.*expect_failed.*|.*slice_\w*_fail.*|.*__rust_start_panic.*)$"
)
DOUBLE = re.compile(r"^(__aeabi_d\w*|__aeabi_[lu]?[il]?2d|__aeabi_f2d|__\w*df[23]\w*|__\w*df\w*)$")
FUNC = re.compile(r"^([0-9a-f]+) <(.+)>:$")
CALL = re.compile(r"^\s*([0-9a-f]+):\s+(bl|blx|b|b\.w|b\.n)\s+(?:0x)?([0-9a-f]+)\s+<([^>]+)>")
INDIRECT = re.compile(r"^\s*([0-9a-f]+):\s+(blx|bx)\s+(r\d+|ip|r1[0-2])\b")


def main() -> int:
    args = sys.argv[1:]
    no_double = "--no-double" in args
    args = [a for a in args if a != "--no-double"]
    if len(args) < (2 if no_double else 3):
        print(__doc__, file=sys.stderr)
        return 2
    objdump, elf, roots = args[0], args[1], args[2:]
    try:
        text = subprocess.run(
            [objdump, "-d", "--no-show-raw-insn", elf], check=True, capture_output=True, text=True
        ).stdout
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"elf_check: cannot disassemble {elf}: {e}", file=sys.stderr)
        return 2
    calls: dict[str, set[str]] = {}
    indirect: dict[str, list[str]] = {}
    cur = None
    for line in text.splitlines():
        m = FUNC.match(line)
        if m:
            cur = m.group(2)
            calls.setdefault(cur, set())
            continue
        if cur is None:
            continue
        m = CALL.match(line)
        if m:
            target = m.group(4)
            base = target.split("+")[0]
            if base != cur:  # branches inside the function are not calls
                calls[cur].add(base)
            continue
        m = INDIRECT.match(line)
        if m and m.group(3) != "lr":
            indirect.setdefault(cur, []).append(line.strip())
    bad = 0
    if no_double:
        doubles = sorted(f for f in calls if DOUBLE.match(f))
        for f in doubles:
            print(f"DOUBLE-PRECISION ROUTINE in the image: {f}")
        bad += len(doubles)
        print(f"image: {len(calls)} functions, {len(doubles)} double-precision routines")
    for root in roots:
        if root not in calls:
            print(f"elf_check: root symbol {root} not in {elf}", file=sys.stderr)
            return 2
        parent = {root: None}
        queue = [root]
        while queue:
            f = queue.pop(0)
            for g in sorted(calls.get(f, ())):
                if g not in parent:
                    parent[g] = f
                    queue.append(g)
        reached = [f for f in parent if FORBIDDEN.match(f)]
        unknown = [f for f in parent if f in indirect]
        for f in reached:
            chain = []
            x = f
            while x is not None:
                chain.append(x)
                x = parent[x]
            print(f"FORBIDDEN from {root}: " + " <- ".join(chain))
            bad += 1
        for f in unknown:
            print(f"INDIRECT CALL from {root} in {f}: {indirect[f][0]}")
            bad += 1
        print(f"{root}: {len(parent)} functions reachable, "
              f"{len(reached)} forbidden, {len(unknown)} with indirect calls")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

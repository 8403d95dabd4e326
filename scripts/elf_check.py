#!/usr/bin/env python3
"""Call-graph check of a Cortex-M ELF: from each root symbol, follow every
direct call and tail call (bl, b, b.w to another function) in the
disassembly, and fail when a forbidden routine is reachable: double-precision
soft float (__aeabi_d*, __aeabi_f2d, libgcc/compiler-builtins *df* routines)
or a panic (core::panicking, rust_begin_unwind, panic handlers). Indirect
calls (blx/bx to a register other than lr) cannot be followed: they fail too.
With --no-double, the whole image must also contain no double-precision
routine at all (reachable from anywhere).

Two more checks for interrupt handlers and tasks, whose driver code is
inlined so that no symbol names it:
  --no-wait ROOT     ROOT and everything it reaches contain no loop (a
                     cycle in the function's control flow from its entry),
                     except the bounded math routines in BOUNDED_LOOPS: a
                     handler that polls a peripheral flag (a blocking ADC
                     read) loops; one raised when the data are ready does
                     not. Panic routines end the flow (a panic halts; it does
                     not wait) and are not followed.
  --calls A=B        every function that calls a function matching regex A
                     also calls one matching regex B (e.g. the task that runs
                     the receive side hands its items through the inbox's
                     `offer`, which keeps slots for Stop/Emergency/ClearFault).
  --loads REGEX=ADDR  every function with a symbol (its label or an alias
                     in the symbol table) matching REGEX loads the address
                     ADDR into a register (movw of its low half, then movt
                     of its high half, same register), and at least one
                     does: the ESC1's panic, HardFault and default handlers
                     reach TIM1's BDTR to turn the power stage off.
Neither forbids panics (the board images are checked with --no-double only).

usage: elf_check.py [--no-double] [--no-wait ROOT]... [--calls A=B]... [--loads R=ADDR]... OBJDUMP ELF [ROOT...]
       elf_check.py --self-test
(roots optional with --no-double, --no-wait, --calls or --loads)
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
# A linker's long-branch thunk is named for its target: judge the target,
# or a Rust symbol whose hash holds "df" reads as a soft-float routine.
THUNK = re.compile(r"^__\w+?(?:LongThunk|ShortThunk|Thunk)_")
FUNC = re.compile(r"^([0-9a-f]+) <(.+)>:$")
CALL = re.compile(r"^\s*([0-9a-f]+):\s+(bl|blx|b|b\.w|b\.n)\s+(?:0x)?([0-9a-f]+)\s+<([^>]+)>")
INDIRECT = re.compile(r"^\s*([0-9a-f]+):\s+(blx|bx)\s+(r\d+|ip|r1[0-2])\b")
INSN = re.compile(r"^\s*([0-9a-f]+):\s+(\S+)\s*(.*)$")
# A line of `objdump -t`: address, flags, section, size, name.
SYM = re.compile(r"^([0-9a-f]+)\s+(.*?)\s+(\S+)\t([0-9a-f]+)\s+(?:\.hidden\s+)?(.+)$")
TARGET = re.compile(r"(?:0x)?([0-9a-f]+)\s+<([^>]+)>")
CONDS = "eq|ne|cs|hs|cc|lo|mi|pl|vs|vc|hi|ls|ge|lt|gt|le"
COND_BRANCH = re.compile(rf"^(b({CONDS})(\.[wn])?|cbn?z)$")
# Routines whose loops are bounded computation, not waiting.
BOUNDED_LOOPS = re.compile(r"^(fminf|fmaxf|sqrtf|fmodf|.*libm.*|__aeabi_mem\w*|mem(cpy|set|move))$")


def symbols(table: str):
    """The lines of `objdump -t`: (address, its Thumb bit cleared; flags;
    size; name) each."""
    for m in map(SYM.match, table.splitlines()):
        if m:
            yield int(m.group(1), 16) & ~1, m.group(2), int(m.group(4), 16), m.group(5)


def real(name: str) -> str:
    """The routine a symbol stands for: a thunk's target, else itself."""
    return THUNK.sub("", name, count=1)


def take(args: list[str], flag: str) -> list[str]:
    """Removes every `flag VALUE` pair from args; returns the values."""
    out = []
    while flag in args:
        i = args.index(flag)
        if i + 1 >= len(args):
            raise SystemExit(f"{flag} needs a value")
        out.append(args[i + 1])
        del args[i : i + 2]
    return out


# --self-test: a handler that polls a flag (as the ESC1's current loop did
# with blocking ADC reads); one with a backward branch that is no cycle and
# bytes after a panic call that disassemble as a branch (as embassy's
# set_duty); a panic's halt; a task that hands items over without `offer`;
# a handler that turns the power stage off and one that only halts.
SELF_TEST = """
08000100 <POLLING>:
 8000100:      \tpush\t{r7, lr}
 8000102:      \tldr\tr3, [r2]
 8000104:      \ttst.w\tr3, #0x4
 8000108:      \tbeq\t0x8000102 <POLLING+0x2> @ imm = #-0xa
 800010a:      \tbl\t0x8000200 <core::panicking::panic>
 800010e:      \tbmi\t0x8000102 <POLLING+0x2> @ imm = #-0x10
08000110 <READY>:
 8000110:      \tpush\t{r7, lr}
 8000112:      \tcmp\tr1, r3
 8000114:      \tbhi\t0x8000120 <READY+0x10> @ imm = #0x8
 8000116:      \tcmp.w\tr1, #0x10000
 800011a:      \tit\tlo
 800011c:      \tpoplo\t{r7, pc}
 800011e:      \tbl\t0x8000200 <core::panicking::panic>
 8000120:      \tadds\tr3, #0x1
 8000122:      \tbls\t0x8000116 <READY+0x6> @ imm = #-0x10
 8000124:      \tbl\t0x8000200 <core::panicking::panic>
 8000128:      \tbmi\t0x8000112 <READY+0x2> @ imm = #-0x1a
08000200 <core::panicking::panic>:
 8000200:      \tb\t0x8000200 <core::panicking::panic> @ imm = #-0x4
08000300 <TASK>:
 8000300:      \tbl\t0x8000400 <Receiver4part>
 8000304:      \tpop\t{r7, pc}
08000400 <Receiver4part>:
 8000400:      \tbx\tlr
08000500 <POWER_OFF>:
 8000500:      \tmovw\tr0, #0x2c44
 8000504:      \tmovt\tr0, #0x4001
 8000508:      \tldr\tr1, [r0]
 800050a:      \tbic\tr1, r1, #0x8000
 800050e:      \tstr\tr1, [r0]
 8000510:      \tb\t0x8000510 <POWER_OFF+0x10>
08000520 <HALT_ONLY>:
 8000520:      \tmovw\tr0, #0x2c44
 8000524:      \tmovt\tr1, #0x4001
 8000528:      \tb\t0x8000528 <HALT_ONLY+0x8>
"""


def self_test() -> int:
    import os
    import tempfile
    with tempfile.TemporaryDirectory() as d:
        dis, cat = os.path.join(d, "x.dis"), os.path.join(d, "cat.sh")
        with open(dis, "w") as f:
            f.write(SELF_TEST)
        with open(cat, "w") as f:
            f.write('#!/bin/sh\n[ "$1" = -t ] && exit 0\ncat "$3"\n')  # no symbol table
        os.chmod(cat, 0o755)
        run = lambda *a: subprocess.run([sys.executable, __file__, *a, cat, dis], capture_output=True).returncode
        got = (run("--no-wait", "POLLING"), run("--no-wait", "READY"), run("--calls", "Receiver4part=offer"),
               run("--loads", "^POWER_OFF$=0x40012C44"), run("--loads", "POWER_OFF|HALT_ONLY=0x40012C44"))
    ok = got == (1, 0, 1, 0, 1)
    print(f"self-test {'passed' if ok else 'FAILED'}: polling, ready, task without offer, "
          f"a handler that loads the address, one that does not (other register) -> {got}")
    return 0 if ok else 1


def main() -> int:
    args = sys.argv[1:]
    if args == ["--self-test"]:
        return self_test()
    no_double = "--no-double" in args
    args = [a for a in args if a != "--no-double"]
    no_wait = take(args, "--no-wait")
    together = [c.split("=", 1) for c in take(args, "--calls")]
    loads = [c.split("=", 1) for c in take(args, "--loads")]
    if any(len(c) != 2 for c in together + loads):
        print("--calls and --loads want A=B", file=sys.stderr)
        return 2
    if len(args) < (2 if no_double or no_wait or together or loads else 3):
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
    code: dict[str, list[tuple[int, str, str]]] = {}
    cur = None
    for line in text.splitlines():
        m = FUNC.match(line)
        if m:
            cur = m.group(2)
            calls.setdefault(cur, set())
            continue
        if cur is None:
            continue
        m = INSN.match(line)
        if m:
            code.setdefault(cur, []).append((int(m.group(1), 16), m.group(2), m.group(3)))
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

    def first_loop(f: str) -> str | None:
        """An instruction closing a cycle of f's control flow, if any."""
        insns = code.get(f, [])
        index = {a: i for i, (a, _, _) in enumerate(insns)}

        def successors(i: int) -> list[int]:
            _, op, rest = insns[i]
            nxt = [i + 1] if i + 1 < len(insns) else []
            t = TARGET.search(rest)
            inside = t is not None and t.group(2).split("+")[0] == f and int(t.group(1), 16) in index
            if op in ("b", "b.w", "b.n"):
                return [index[int(t.group(1), 16)]] if inside else []
            if COND_BRANCH.match(op):
                return nxt + ([index[int(t.group(1), 16)]] if inside else [])
            if op in ("bl", "blx") and t is not None and FORBIDDEN.match(real(t.group(2).split("+")[0])):
                return []  # a panic does not return
            if op in ("udf", "bkpt") or (op in ("pop", "pop.w", "ldm", "ldmia.w") and "pc" in rest):
                return []
            if op in ("bx", "bx.n") and "lr" in rest:
                return []
            return nxt

        state = [0] * len(insns)  # 0 new, 1 on the path, 2 done
        stack = [(0, iter(successors(0)))] if insns else []
        if insns:
            state[0] = 1
        while stack:
            i, it = stack[-1]
            j = next(it, None)
            if j is None:
                state[i] = 2
                stack.pop()
            elif state[j] == 1:
                a, op, rest = insns[i]
                return f"{a:x}: {op} {rest}"
            elif state[j] == 0:
                state[j] = 1
                stack.append((j, iter(successors(j))))
        return None

    def reach(root: str) -> dict:
        parent = {root: None}
        queue = [root]
        while queue:
            f = queue.pop(0)
            for g in sorted(calls.get(f, ())):
                if g not in parent:
                    parent[g] = f
                    queue.append(g)
        return parent

    for root in no_wait:
        if root not in calls:
            print(f"elf_check: root symbol {root} not in {elf}", file=sys.stderr)
            return 2
        parent = {root: None}
        queue = [root]
        while queue:  # as reach(), but panic routines are not followed
            f = queue.pop(0)
            for g in sorted(calls.get(f, ())):
                if g not in parent and not FORBIDDEN.match(real(g)):
                    parent[g] = f
                    queue.append(g)
        waiting = []
        for f in parent:
            at = None if BOUNDED_LOOPS.match(f) else first_loop(f)
            if at:
                waiting.append(f)
                print(f"LOOP (a wait) reached from {root} in {f}: {at}")
        bad += len(waiting)
        print(f"{root}: {len(parent)} functions reachable, {len(waiting)} with loops")
    for a, b in together:
        ra, rb = re.compile(a), re.compile(b)
        callers = sorted(f for f, cs in calls.items() if any(ra.search(c) for c in cs))
        if not callers:
            print(f"elf_check: nothing calls {a} in {elf}", file=sys.stderr)
            return 2
        for f in callers:
            ok = any(rb.search(c) for c in calls[f])
            print(f"{'ok' if ok else 'MISSING'}: {f} calls {a}{' and ' if ok else ' but not '}{b}")
            bad += not ok
    if loads:
        try:
            table = subprocess.run([objdump, "-t", elf], check=True, capture_output=True, text=True).stdout
        except (OSError, subprocess.CalledProcessError) as e:
            print(f"elf_check: cannot read the symbols of {elf}: {e}", file=sys.stderr)
            return 2
        names: dict[int, set[str]] = {}
        for a, _, _, name in symbols(table):
            names.setdefault(a, set()).add(name)
        starts = {f: a for f, insns in code.items() for a in [insns[0][0]] if insns}
    for pattern, addr in loads:
        rx, value = re.compile(pattern), int(addr, 0)
        lo, hi = f"#0x{value & 0xFFFF:x}", f"#0x{value >> 16:x}"
        hits = [f for f, a in starts.items() if rx.search(f) or any(rx.search(n) for n in names.get(a, ()))]
        if not hits:
            print(f"elf_check: no function matches {pattern} in {elf}", file=sys.stderr)
            return 2
        for f in hits:
            low = {rest.split(",")[0] for _, op, rest in code[f] if op.startswith("movw") and rest.endswith(lo)}
            ok = any(op.startswith("movt") and rest.split(",")[0] in low and rest.endswith(hi)
                     for _, op, rest in code[f])
            print(f"{'ok' if ok else 'MISSING'}: {f} loads {value:#x}")
            bad += not ok
    if no_double:
        doubles = sorted(f for f in calls if DOUBLE.match(real(f)))
        for f in doubles:
            print(f"DOUBLE-PRECISION ROUTINE in the image: {f}")
        bad += len(doubles)
        print(f"image: {len(calls)} functions, {len(doubles)} double-precision routines")
    for root in roots:
        if root not in calls:
            print(f"elf_check: root symbol {root} not in {elf}", file=sys.stderr)
            return 2
        parent = reach(root)
        reached = [f for f in parent if FORBIDDEN.match(real(f))]
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

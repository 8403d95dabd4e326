#!/usr/bin/env python3
"""Static worst-case stack depth of a Cortex-M (Thumb-2) ELF, against the
room that RAM leaves the stack (cortex-m-rt puts it at the end of RAM,
growing down into .bss).

Frame of a function: the sum of every stack-decreasing instruction anywhere
in it (push, push.w, stmdb/vstmdb sp!, vpush, sub sp by an immediate or by a
register set by movw/movt/mov in the same function, str Rx, [sp, #-N]!, a
realignment `bfc Rx, #0, #k` moved into sp counts 2^k - 4), so shrink-wrapped
pushes count as if nested. Restores (pop, vpop, add sp, ldm sp!, mov sp from
the frame pointer) are ignored. A sub sp by a register whose value is not
found is an UNKNOWN FRAME; any other write of sp is UNCLASSIFIED: both fail.

Call graph: bl, and b/b.w/b<cond> to another function's entry (tail calls),
a linker thunk standing for its target. A conditional branch into the middle
of another function is not a call (llvm-objdump decodes the 0xd4d4 padding
after a function's last return as `bmi <next+0x..>`). Indirect calls (blx/bx
to a register other than lr) must be resolved:
  --indirect CALLER=TARGET  every indirect call in a function matching regex
                            CALLER may reach every function matching regex
                            TARGET (regexes are searched in a function's
                            symbols and demangled name; mappings add up).
An unresolved indirect call, or recursion (a cycle), fails, unless
  --reentry REGEX           every function matching REGEX may be active twice
                            on a call chain (a recursion one level deep, by an
                            argument about the code that the caller makes:
                            all functions of the cycle must match); a third
                            entry is taken as not made.

Depth of a root: its frame + the deepest of its callees. Preemption:
  --thread ROOT      a thread-mode root (repeatable: the deepest counts)
  --level A,B,...    the handlers of one interrupt priority level (repeat
                     once per level, in any order): handlers of a level do
                     not preempt each other; each level may preempt the
                     thread and every other level, so the worst is
                     thread + sum over levels of (deepest handler + 108 B).
Budget: room = LENGTH of the RAM region in --memory-x PATH (a linker
memory.x) - (.data + .bss + .uninit, from `objdump -h`), or cortex-m-rt's
_stack_start - _stack_end where the image defines both and that is smaller;
fails when worst + --margin (default 256) > room, unless
  --known-short B    the image is known not to fit by up to B bytes: it
                     passes, saying DOES NOT FIT, while worst + margin -
                     room <= B (a ratchet: the shortfall may not grow).

usage: stack_check.py --memory-x PATH [--margin B] [--known-short B] [--indirect C=T]... [--reentry R]...
                      --thread ROOT... [--level A,B,...]... OBJDUMP ELF
       stack_check.py --self-test
exit 0 within budget, 1 violation, 2 usage/tool error (or a root symbol or
an --indirect target missing from the image).
"""
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from elf_check import COND_BRANCH, FUNC, INDIRECT, INSN, TARGET, THUNK, real, symbols, take  # noqa: E402

# The Cortex-M4F's exception entry stacks R0-R3, R12, LR, PC, xPSR (8 words)
# and, with the FPU in use (CONTROL.FPCA, lazy stacking reserves the space
# anyway), S0-S15, FPSCR and a reserved word (18 words): 104 B. With
# CCR.STKALIGN (set out of reset on the M4) the frame starts 8-byte aligned,
# which may cost 4 B of padding: 108 B per preempting level.
EXCEPTION_FRAME = 108
SECTION = re.compile(r"^\s*\d+\s+(\S+)\s+([0-9a-f]+)\s+[0-9a-f]+")
IMM = re.compile(r"#(-?(?:0x[0-9a-f]+|\d+))")
REGION = re.compile(r"\bRAM\s*(?:\([^)]*\))?\s*:\s*ORIGIN\s*=\s*[^,]+,\s*LENGTH\s*=\s*(0x[0-9a-fA-F]+|\d+)\s*([KM]?)")
NOT_WRITING = ("st", "cmp", "cmn", "tst", "teq", "vst", "pld")


class Fail(Exception):
    """A usage or tool error (exit 2)."""


def demangle(name: str) -> str:
    """Rust legacy (_ZN...17h<hash>E) and v0 (_R, plain paths) names made readable."""
    m = re.match(r"^_ZN(.*)E$", name)
    if m:
        s, parts = m.group(1), []
        while s and s[0].isdigit():
            n = re.match(r"\d+", s).group(0)
            parts.append(s[len(n) : len(n) + int(n)])
            s = s[len(n) + int(n) :]
        if s or not parts:
            return name
        if re.fullmatch(r"h[0-9a-f]{16}", parts[-1]):
            parts.pop()
        out = []
        for p in parts:
            p = p[1:] if p.startswith("_$") else p
            p = re.sub(r"\$u([0-9a-f]+)\$", lambda u: chr(int(u.group(1), 16)), p)
            for k, v in (("$LT$", "<"), ("$GT$", ">"), ("$C$", ","), ("$RF$", "&"), ("$BP$", "*"),
                         ("$SP$", "@"), ("$LP$", "("), ("$RP$", ")"), ("..", "::")):
                p = p.replace(k, v)
            out.append(p)
        return "::".join(out)
    if name.startswith("_R"):
        pos = 2

        def path() -> str:
            nonlocal pos
            tag = name[pos]
            pos += 1
            if tag == "N":
                pos += 1  # namespace letter
                inner = path()
                return f"{inner}::{ident()}"
            if tag == "C":
                return ident()
            raise ValueError(tag)

        def ident() -> str:
            nonlocal pos
            if name[pos] == "s":  # disambiguator s<base62>_
                pos = name.index("_", pos) + 1
            n = re.match(r"\d+", name[pos:]).group(0)
            pos += len(n)
            pos += name[pos] == "_"
            s = name[pos : pos + int(n)]
            pos += int(n)
            return s

        try:
            return path()
        except (ValueError, IndexError, AttributeError):
            return name
    return name


def reg_count(rest: str) -> list[str]:
    """The registers of a register list {r4-r7, lr}, {d8-d15}, one per entry."""
    m = re.search(r"\{([^}]*)\}", rest)
    regs = []
    for item in (m.group(1).split(",") if m else []):
        item = item.strip()
        r = re.fullmatch(r"([a-z]+)(\d+)-([a-z]+)(\d+)", item)
        if r:
            regs += [r.group(1)] * (int(r.group(4)) - int(r.group(2)) + 1)
        elif item:
            regs.append(item[0] if re.fullmatch(r"[ds]\d+", item) else "r")
    return regs


def list_bytes(rest: str) -> int:
    """Bytes a push of the register list in rest stores: 8 per d register, else 4."""
    return sum(8 if r == "d" else 4 for r in reg_count(rest))


def last_write(insns: list, i: int, reg: str) -> int | None:
    """Index of the last instruction before i whose destination is reg."""
    for j in range(i - 1, -1, -1):
        _, op, rest = insns[j]
        if rest.split(",")[0].strip() == reg and not op.startswith(NOT_WRITING):
            return j
    return None


def reg_value(insns: list, i: int, reg: str) -> int | None:
    """The constant set into reg before i by movw (+movt) or mov, else None."""
    j = last_write(insns, i, reg)
    hi = None
    if j is not None and insns[j][1] == "movt":
        hi = int(IMM.search(insns[j][2]).group(1), 0)
        j = last_write(insns, j, reg)
    if j is None or insns[j][1] not in ("movw", "mov", "movs", "mov.w", "movw.w"):
        return None
    m = IMM.search(insns[j][2])
    if not m:
        return None
    lo = int(m.group(1), 0) & 0xFFFFFFFF
    return (hi << 16 | lo & 0xFFFF) if hi is not None else lo


def frame(insns: list) -> tuple[int, list[str]]:
    """A function's frame in bytes and the problems found (unknown frame,
    unclassified writes of sp)."""
    size, bad = 0, []
    for i, (a, op, rest) in enumerate(insns):
        ops = [o.strip() for o in rest.split(",")]
        where = f"{a:x}: {op} {rest}"
        if re.match(r"^v?(push|pop)", op):
            if op.startswith(("push", "vpush")):
                size += list_bytes(rest)
            continue
        writes = ("sp!" in rest or re.search(r"\[sp\], #|\[sp, #[^\]]*\]!", rest)
                  or (ops[0] == "sp" and not op.startswith(NOT_WRITING))
                  or (op.startswith("msr") and ops[0] in ("msp", "psp")))
        if not writes:
            continue
        if re.match(r"^v?(stmdb|stmfd)", op) and rest.startswith("sp!"):
            size += list_bytes(rest)
        elif re.match(r"^v?ldm", op) and rest.startswith("sp!"):
            pass  # pop
        elif re.match(r"^(ldr|vldr)", op) and re.search(r"\[sp\], #\d|\[sp, #(0x[0-9a-f]+|\d+)\]!", rest):
            pass  # a pop by a load that raises sp
        elif op.startswith("str") and (pre := re.search(r"\[sp, #-(0x[0-9a-f]+|\d+)\]!", rest)):
            size += int(pre.group(1), 0)
        elif op.startswith("add") and ops[0] == "sp":
            pass  # restore
        elif op.startswith("sub") and ops[0] == "sp":
            m = IMM.search(ops[-1])
            if m:
                size += int(m.group(1), 0)
            elif len(ops) in (2, 3) and re.fullmatch(r"r\d+|ip|lr", ops[-1]):
                v = reg_value(insns, i, ops[-1])
                if v is None:
                    bad.append(f"UNKNOWN FRAME: sp lowered by a register whose value is not found: {where}")
                else:
                    size += v
            else:
                bad.append(f"UNKNOWN FRAME: {where}")
        elif op.startswith("mov") and ops[0] == "sp" and len(ops) == 2:
            src = ops[1]
            j = last_write(insns, i, src)
            prev = insns[j] if j is not None else (0, "", "")
            bfc = re.fullmatch(rf"{src}, #0, #(\d+)", prev[2]) if prev[1] == "bfc" else None
            if bfc:
                size += 2 ** int(bfc.group(1)) - 4  # realignment
            elif src in ("r7", "r11") or (prev[1].startswith(("mov", "sub", "add"))
                                          and re.match(rf"^{src}, (r7|r11)\b", prev[2])):
                pass  # back to the frame pointer: a restore
            else:
                bad.append(f"UNCLASSIFIED write of sp: {where}")
        else:
            bad.append(f"UNCLASSIFIED write of sp: {where}")
    return size, bad


def analyse(dis: str, syms: str, thread: list[str], levels: list[list[str]], indirect: list[tuple[str, str]],
            reentry: tuple[str, ...] = ()) -> dict:
    """Frames, call graph and depths. Raises Fail on a missing root or an
    --indirect target matching nothing; returns the report's data."""
    code: dict[int, list] = {}
    head: dict[str, int] = {}
    names: dict[int, list[str]] = {}
    cur = None
    for line in dis.splitlines():
        m = FUNC.match(line)
        if m:
            cur = int(m.group(1), 16)
            head[m.group(2)] = cur
            code[cur] = []
            names[cur] = [m.group(2)]
            continue
        m = INSN.match(line)
        if m and cur is not None and not re.fullmatch(r"[0-9a-f]{2}", m.group(2)):  # not a .word's raw bytes
            code[cur].append((int(m.group(1), 16), m.group(2), m.group(3)))
    by_name = dict(head)
    preferred: dict[int, str] = {}
    for addr, flags, size, name in symbols(syms):
        if addr in code and not name.startswith("$"):
            by_name.setdefault(name, addr)
            if name not in names[addr]:
                names[addr].append(name)
            if " F " in f" {flags} " and size and addr not in preferred:
                preferred[addr] = name
    label = {a: demangle(preferred.get(a, names[a][0])) for a in code}
    every = {a: names[a] + [demangle(n) for n in names[a]] for a in code}

    frames, problems, calls, sites = {}, {}, {}, {}
    for a, insns in code.items():
        frames[a], problems[a] = frame(insns)
        own = names[a][0]
        calls[a], sites[a] = set(), []
        for ia, op, rest in insns:
            t = TARGET.search(rest)
            if t and (op in ("bl", "blx", "b", "b.w", "b.n") or COND_BRANCH.match(op) and "+" not in t.group(2)):
                base = t.group(2).split("+")[0]
                if base == own and op not in ("bl", "blx"):
                    continue  # a branch inside the function
                callee = by_name.get(real(base))
                if callee is None:
                    problems[a].append(f"UNKNOWN CALLEE {real(base)}: {ia:x}: {op} {rest}")
                else:
                    calls[a].add(callee)
            elif INDIRECT.match(f" {ia:x}: {op} {rest}") and not rest.startswith("lr") and not THUNK.match(own):
                sites[a].append(f"{ia:x}: {op} {rest}")
    matching = lambda rx: {a for a in code if any(re.search(rx, n) for n in every[a])}
    for c, t in indirect:
        targets = matching(t)
        if not targets:
            raise Fail(f"--indirect {c}={t}: no function matches {t}")
        for a in matching(c):
            calls[a] |= targets if sites[a] else set()
    resolved = {a for a in code if any(re.search(c, n) for c, _ in indirect for n in every[a])}

    def root(n: str) -> int:
        if n not in by_name:
            raise Fail(f"root symbol {n} not in the image")
        return by_name[n]

    again = {a for a in code if any(re.search(rx, n) for rx in reentry for n in every[a])}
    # A function's depth depends on which --reentry functions are active
    # above it: memoised per (function, those functions on the chain).
    memo: dict[tuple, tuple[int, tuple | None]] = {}
    path: list[int] = []
    cycles: list[str] = []
    reached: set[int] = set()

    def walk(a: int) -> tuple | None:
        if a in path and (a not in again or path.count(a) >= 2):
            if a not in again:
                cycles.append(" -> ".join(label[x] for x in path[path.index(a):] + [a]))
            return None  # a recursion (an error), or a third entry declared not to happen
        key = (a, tuple(sorted(x for x in path if x in again)))
        if key in memo:
            return key
        reached.add(a)
        path.append(a)
        deep, pick = 0, None
        for c in sorted(calls[a]):
            k = walk(c)
            if k is not None and (pick is None or memo[k][0] > deep):
                deep, pick = memo[k][0], k
        path.pop()
        memo[key] = (frames[a] + deep, pick)
        return key

    def chain(n: str) -> tuple[int, list[tuple[str, int]]]:
        k = walk(root(n))
        out = []
        while k is not None:
            out.append((f"{n if not out else label[k[0]]}  @{k[0]:x}", frames[k[0]]))
            k = memo[k][1]
        return memo[walk(root(n))][0], out

    sys.setrecursionlimit(max(10000, 4 * len(code)))
    result = {"thread": [], "levels": [], "cycles": cycles, "errors": []}
    for n in thread:
        result["thread"].append((n, *chain(n)))
    for level in levels:
        result["levels"].append([(n, *chain(n)) for n in level])
    for a in sorted(reached):
        result["errors"] += [f"{label[a]}: {p}" for p in problems[a]]
        if sites[a] and a not in resolved:
            result["errors"] += [f"UNRESOLVED INDIRECT CALL in {label[a]}: {s}" for s in sites[a]]
    result["errors"] += [f"RECURSION: {c}" for c in cycles]
    result["frames"] = sorted(((frames[a], f"{label[a]}  @{a:x}") for a in reached), reverse=True)
    result["unreached_problems"] = [f"{label[a]}: {p}" for a in code if a not in reached for p in problems[a]]
    t = max((d for _, d, _ in result["thread"]), default=0)
    result["worst"] = t + sum(max(d for _, d, _ in lv) + EXCEPTION_FRAME for lv in result["levels"])
    result["thread_worst"] = t
    return result


def room(sections: str, memory_x: str) -> int:
    """RAM region length - (.data + .bss + .uninit)."""
    text = re.sub(r"/\*.*?\*/", "", memory_x, flags=re.S)
    m = REGION.search(text)
    if not m:
        raise Fail("no `RAM : ORIGIN = ..., LENGTH = ...` region in the memory.x")
    ram = int(m.group(1), 0) * {"": 1, "K": 1024, "M": 1 << 20}[m.group(2)]
    used = sum(int(s.group(2), 16) for s in map(SECTION.match, sections.splitlines())
               if s and s.group(1) in (".data", ".bss", ".uninit"))
    return ram - used


def report(r: dict, rm: int, margin: int, extra: str = "", known_short: int = 0) -> int:
    def show(title: str, n: str, d: int, ch: list) -> None:
        print(f"{title} {n}: {d} B")
        for name, f in ch:
            print(f"  {f:6}  {name}")

    for n, d, ch in r["thread"]:
        show("thread", n, d, ch)
    for i, lv in enumerate(r["levels"]):
        for n, d, ch in lv:
            show(f"level {i + 1} handler", n, d, ch)
    print("largest frames of the functions reached:")
    for f, n in r["frames"][:10]:
        print(f"  {f:6}  {n}")
    for p in r["unreached_problems"]:
        print(f"note (not reached from the roots): {p}")
    for e in r["errors"]:
        print(e)
    levels = " + ".join(f"{max(d for _, d, _ in lv)}+{EXCEPTION_FRAME}" for lv in r["levels"])
    print(f"stack: worst {r['worst']} B (thread {r['thread_worst']} + levels {levels or 'none'}), "
          f"room {rm} B, margin {margin} B{extra}")
    short = r["worst"] + margin - rm
    over = short > known_short
    if over:
        print(f"FAIL: worst stack {r['worst']} B + margin {margin} B exceeds the room of {rm} B "
              f"by {short} B{f' (at most {known_short} B known)' if known_short else ''}")
    elif short > 0:
        # A ratchet while the image is known not to fit: it may not get worse.
        print(f"DOES NOT FIT: short by {short} B (at most {known_short} B known; "
              f"lower --known-short when this falls)")
    return 1 if r["errors"] or over else 0


# --self-test: push ranges, vpush, sub sp by an immediate and by a register
# set by movw/movt, a realignment, a tail call, a thunk, an indirect call
# resolved by --indirect, an unresolved one, recursion, and the preemption sum.
SELF_TEST = """
08000100 <Reset>:
 8000100:      \tpush\t{r4-r7, lr}
 8000102:      \tpush.w\t{r8, r9, r10, r11}
 8000106:      \tvpush\t{d8-d15}
 800010a:      \tsub\tsp, #0x10
 800010c:      \tbl\t0x8000200 <LEAF>
 8000110:      \tadd\tsp, #0x10
 8000112:      \tpop\t{r4-r7, pc}
 8000114:      \tbmi\t0x80001a8 <BIG+0x8> @ imm = #-0x58
08000120 <BIG>:
 8000120:      \tpush\t{r7, lr}
 8000122:      \tmovw\tr4, #0x1234
 8000126:      \tmovt\tr4, #0x0
 800012a:      \tsub.w\tsp, sp, r4
 800012e:      \tmov\tr4, sp
 8000130:      \tbfc\tr4, #0, #4
 8000134:      \tmov\tsp, r4
 8000136:      \tstr\tr0, [sp, #-8]!
 800013a:      \tmov\tsp, r7
 800013c:      \tpop\t{r7, pc}
08000140 <TAIL>:
 8000140:      \tsub.w\tsp, sp, #0x100
 8000144:      \tadd.w\tsp, sp, #0x100
 8000148:      \tb.w\t0x8000200 <LEAF>
08000150 <VIA_THUNK>:
 8000150:      \tpush\t{r7, lr}
 8000152:      \tbl\t0x8000300 <__Thumbv7ABSLongThunk_BIG>
 8000156:      \tpop\t{r7, pc}
08000160 <DISPATCH>:
 8000160:      \tpush\t{r4, lr}
 8000162:      \tldr\tr1, [r0, #0x24]
 8000164:      \tblx\tr1
 8000166:      \tpop\t{r4, pc}
08000170 <LOOP_A>:
 8000170:      \tpush\t{r7, lr}
 8000172:      \tbl\t0x8000180 <LOOP_B>
 8000176:      \tpop\t{r7, pc}
08000180 <LOOP_B>:
 8000180:      \tpush\t{r7, lr}
 8000182:      \tbl\t0x8000170 <LOOP_A>
 8000186:      \tpop\t{r7, pc}
08000190 <NOVALUE>:
 8000190:      \tsub\tsp, r2
 8000192:      \tbx\tlr
08000200 <LEAF>:
 8000200:      \tsubw\tsp, sp, #0x40
 8000204:      \tvpush\t{s16, s17}
 8000208:      \tbx\tlr
08000300 <__Thumbv7ABSLongThunk_BIG>:
 8000300:      \tmovw\tip, #0x121
 8000304:      \tmovt\tip, #0x800
 8000308:      \tbx\tr12
"""
SELF_SYMS = """
08000100 g     F .text\t00000014 Reset
08000160 g     F .text\t00000008 TIM6_DAC
08000150 g     F .text\t00000008 ADC1_2
08000140 g     F .text\t00000008 FDCAN1_IT0
"""
SELF_SECTIONS = """
  5 .data           00000010 20000000 0801e0c8 DATA
  7 .bss            00000100 20000010 20000010 BSS
  8 .uninit         00000000 20000110 20000110 BSS
"""


def self_test() -> int:
    leaf = 0x40 + 8  # subw 0x40 + vpush {s16, s17}
    big = 8 + 0x1234 + (16 - 4) + 8  # push, sub by r4 (movw/movt), realignment, str [sp, #-8]!
    reset = 20 + 16 + 64 + 16 + leaf
    tail = 0x100 + leaf  # tail call: the frame counted although popped first
    thunk = 8 + big
    dispatch = 8 + max(tail, thunk)
    fails = []
    r = analyse(SELF_TEST, SELF_SYMS, ["Reset"], [["TIM6_DAC"], ["ADC1_2", "FDCAN1_IT0"]],
                [("DISPATCH", "^(TAIL|VIA_THUNK)$")])
    want = reset + (dispatch + 108) + (max(thunk, tail) + 108)
    got = (r["thread_worst"], [[d for _, d, _ in lv] for lv in r["levels"]], r["worst"], r["errors"])
    if got != (reset, [[dispatch], [thunk, tail]], want, []):
        fails.append(f"depths {got}, want {(reset, [[dispatch], [thunk, tail]], want, [])}")
    r = analyse(SELF_TEST, SELF_SYMS, ["Reset"], [["DISPATCH"]], [])
    if not any("UNRESOLVED INDIRECT CALL in TIM6_DAC: 8000164: blx r1" in e for e in r["errors"]):
        fails.append(f"unresolved indirect call not reported: {r['errors']}")
    r = analyse(SELF_TEST, SELF_SYMS, ["LOOP_A", "NOVALUE"], [], [])
    if not any(e.startswith("RECURSION: LOOP_A -> LOOP_B -> LOOP_A") for e in r["errors"]) or \
            not any("UNKNOWN FRAME" in e and "NOVALUE" in e for e in r["errors"]):
        fails.append(f"recursion or unknown frame not reported: {r['errors']}")
    for bad in (lambda: analyse(SELF_TEST, SELF_SYMS, ["Reset"], [["EXTI9_5"]], []),
                lambda: analyse(SELF_TEST, SELF_SYMS, ["Reset"], [], [("DISPATCH", "NOSUCH")])):
        try:
            bad()
            fails.append("a missing root or --indirect target passed")
        except Fail:
            pass
    r = analyse(SELF_TEST, SELF_SYMS, ["LOOP_A"], [], [], ("LOOP_",))
    if (r["thread_worst"], r["errors"]) != (32, []):
        fails.append(f"--reentry LOOP_: {r['thread_worst']} {r['errors']}, want 32 (A B A B)")
    _, bad_sp = frame([(0, "ldr", "sp, [r0]"), (2, "mov", "sp, r3")])
    if len(bad_sp) != 2:
        fails.append(f"unclassified sp writes: {bad_sp}")
    rm = room(SELF_SECTIONS, "MEMORY { RAM : ORIGIN = 0x20000000, LENGTH = 8K /* x */ }")
    if rm != 8192 - 0x110:
        fails.append(f"room {rm}")
    # The ratchet: short by 100 B passes with 100 known, fails with 99.
    r = {"thread": [], "levels": [], "frames": [], "unreached_problems": [], "errors": [],
         "worst": 1000, "thread_worst": 1000}
    import contextlib
    import io
    with contextlib.redirect_stdout(io.StringIO()):
        ratchet = (report(r, 1000, 100), report(r, 1000, 100, "", 100), report(r, 1000, 100, "", 99))
    if ratchet != (1, 0, 1):
        fails.append(f"--known-short: {ratchet}, want (1, 0, 1)")
    print(f"self-test {'passed' if not fails else 'FAILED'}: Reset {reset}, levels {dispatch}+108, "
          f"{max(thunk, tail)}+108, worst {want}; reentry 32; unresolved, recursion, unknown frame, "
          "unclassified sp writes, missing root fail; --known-short holds its bound")
    for f in fails:
        print(f"  {f}")
    return 1 if fails else 0


def main() -> int:
    args = sys.argv[1:]
    if args == ["--self-test"]:
        return self_test()
    try:
        memory_x = take(args, "--memory-x")
        margin = [int(m, 0) for m in take(args, "--margin")] or [256]
        known_short = [int(m, 0) for m in take(args, "--known-short")] or [0]
        pairs = [i.split("=", 1) for i in take(args, "--indirect")]
        thread = take(args, "--thread")
        reentry = tuple(take(args, "--reentry"))
        levels = [[h.strip() for h in lv.split(",") if h.strip()] for lv in take(args, "--level")]
        if any(len(p) != 2 for p in pairs):
            raise SystemExit("--indirect wants CALLER=TARGET")
        for rx in [x for p in pairs for x in p] + list(reentry):
            re.compile(rx)
    except (SystemExit, ValueError, re.error) as e:
        print(f"stack_check: {e}", file=sys.stderr)
        return 2
    if len(args) != 2 or len(memory_x) != 1 or not thread or any(not lv for lv in levels):
        print(__doc__, file=sys.stderr)
        return 2
    objdump, elf = args

    def dump(*flags: str) -> str:
        return subprocess.run([objdump, *flags, elf], check=True, capture_output=True, text=True).stdout

    try:
        dis, syms, sections = dump("-d", "--no-show-raw-insn"), dump("-t"), dump("-h")
        with open(memory_x[0]) as f:
            rm = room(sections, f.read())
        r = analyse(dis, syms, thread, levels, [(c, t) for c, t in pairs], reentry)
    except (OSError, subprocess.CalledProcessError) as e:
        print(f"stack_check: cannot read {elf}: {e}", file=sys.stderr)
        return 2
    except Fail as e:
        print(f"stack_check: {e}", file=sys.stderr)
        return 2
    # cortex-m-rt's own symbols for the stack's ends, where it defines them:
    # a cross-check of the room computed from memory.x and the sections.
    ends = {name: a for a, _, _, name in symbols(syms) if name in ("_stack_start", "_stack_end")}
    extra = ""
    if len(ends) == 2 and ends["_stack_start"] - ends["_stack_end"] != rm:
        extra = f" (_stack_start - _stack_end = {ends['_stack_start'] - ends['_stack_end']} B: using the smaller)"
        rm = min(rm, ends["_stack_start"] - ends["_stack_end"])
    return report(r, rm, margin[-1], extra, known_short[-1])


if __name__ == "__main__":
    sys.exit(main())

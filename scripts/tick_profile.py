#!/usr/bin/env python3
"""Where the control tick's instructions go, measured: runs the QEMU test
image with `-d in_asm,exec,nochain` (every translated block and every block
executed), keeps the blocks executed between entering ROOT and returning to a
function outside ROOT's call graph, and attributes each executed instruction
to its source line (llvm-objdump -dl: the innermost inlined line) or to the
called routine. Prints instructions per tick by component.

usage: tick_profile.py OBJDUMP ELF ROOT -- QEMU-COMMAND...
"""
import collections
import re
import subprocess
import sys

sys.path.insert(0, __file__.rsplit("/", 1)[0])
FUNC = re.compile(r"^([0-9a-f]+) <(.+)>:$")
INSN = re.compile(r"^\s*([0-9a-f]+):\s")
LINE = re.compile(r"^; (.+):(\d+)$")
CALL = re.compile(r"^\s*[0-9a-f]+:\s+(bl|b|b\.w|b\.n)\s+(?:0x)?[0-9a-f]+\s+<([^>+]+)")

# (source path fragment, function name fragment) -> component; first match wins.
COMPONENTS = [
    ("firmware/src/segment.rs", "", "quintic evaluation, 3 axes (Seg::eval, scale)"),
    ("shared/src/quintic.rs", "", "quintic evaluation, 3 axes (Seg::eval, scale)"),
    ("shared/src/kinematics.rs", "", "inverse dynamics: pose, Jacobians"),
    ("shared/src/dynamics.rs", "", "inverse dynamics: virtual work"),
    ("firmware/src/scaling.rs", "", "time-scaling sigma(t), plan time"),
    ("firmware/src/sync.rs", "", "host time from the sync estimate"),
    ("shared/src/protocol", "", "frame encoding (heartbeat, telemetry)"),
    ("firmware/src/drive.rs", "take", "hand-off: items taken from the inbox"),
    ("firmware/src/drive.rs", "accept", "hand-off: items taken from the inbox"),
    ("firmware/src/drive.rs", "commit", "hand-off: items taken from the inbox"),
    ("firmware/src/drive.rs", "on_command", "hand-off: items taken from the inbox"),
    ("heapless", "", "hand-off: items taken from the inbox"),
    ("firmware/src/drive.rs", "periodic", "frame encoding (heartbeat, telemetry)"),
    ("firmware/src/drive.rs", "lookahead", "queue search (lookahead, advance)"),
    ("firmware/src/drive.rs", "path_reference", "queue search (lookahead, advance)"),
    ("firmware/src/drive.rs", "", "drive: state machine, PID, velocity filter, friction"),
]


def component(chain: list[tuple[str, str]], symbol: str) -> str:
    """chain: (function, file:line) innermost first, from addr2line -i."""
    if symbol.startswith("__aeabi_mem") or symbol in ("memcpy", "memset", "memmove"):
        return "memcpy/memset (struct copies)"
    if symbol.startswith("__"):
        return "runtime: 64-bit integer division, int<->float conversion"
    if any("libm" in f for _, f in chain):
        return "friction tanh (libm expf)"
    for func, src in chain:
        for path, name, comp in COMPONENTS:
            if path in src and name in func:
                return comp
    return f"other ({symbol})"


def cycles(cnt: collections.Counter, mnemonic: dict[int, str]) -> tuple[int, int]:
    """A per-instruction Cortex-M4 cycle estimate (ARM DDI 0439 timings, pessimistic
    where they vary): VDIV/VSQRT 14, loads 2, load/store multiple 1 + registers,
    branches 3 (as if taken), integer divide 12, everything else 1."""
    total, divs = 0, 0
    for a, n in cnt.items():
        m = mnemonic.get(a, "")
        op = m.split()[0] if m else ""
        if op.startswith(("vdiv", "vsqrt")):
            c = 14
            divs += n
        elif op.startswith(("udiv", "sdiv")):
            c = 12
        elif op.startswith(("ldm", "stm", "push", "pop", "vpush", "vpop", "vldm", "vstm")):
            c = 1 + max(1, m.count(",") + 1)
        elif op.startswith(("ldr", "vldr")):
            c = 2
        elif op.startswith(("b", "cb")) and not op.startswith(("bic", "bfi", "bfc")):
            c = 3
        else:
            c = 1
        total += c * n
    return total, divs


def symbolize(elf: str, addrs: list[int]) -> dict[int, list[tuple[str, str]]]:
    """addr -> inline chain, one addr2line run (frames end at a sentinel address 0)."""
    query = "".join(f"0x{a:x}\n0x0\n" for a in addrs)
    out = subprocess.run(["addr2line", "-i", "-f", "-C", "-e", elf], input=query,
                         capture_output=True, text=True, check=True).stdout.splitlines()
    res: dict[int, list[tuple[str, str]]] = {}
    i = 0
    for a in addrs:
        chain = []
        # Address 0 symbolises as the vector table with no line: the sentinel.
        while i + 1 < len(out) and not out[i + 1].startswith("??"):
            chain.append((out[i], out[i + 1]))
            i += 2
        i += 2
        res[a] = chain
    return res


def main() -> int:
    if "--" not in sys.argv:
        print(__doc__, file=sys.stderr)
        return 2
    k = sys.argv.index("--")
    objdump, elf, root = sys.argv[1:k]
    qemu = sys.argv[k + 1:]
    dis = subprocess.run([objdump, "-dl", "--no-show-raw-insn", elf], check=True,
                         capture_output=True, text=True).stdout
    where: dict[int, tuple[str, str]] = {}
    mnemonic: dict[int, str] = {}
    funcs: dict[str, set[str]] = collections.defaultdict(set)
    func_of: dict[int, str] = {}
    cur, src = "", ""
    for line in dis.splitlines():
        m = FUNC.match(line)
        if m:
            cur, src = m.group(2), ""
            continue
        m = LINE.match(line)
        if m:
            src = f"{m.group(1)}:{m.group(2)}"
            continue
        m = INSN.match(line)
        if m and cur:
            a = int(m.group(1), 16)
            parts = line.split("\t")
            mnemonic[a] = parts[1].strip() if len(parts) > 1 else ""
            where[a] = (cur, src)
            func_of[a] = cur
            c = CALL.match(line)
            if c and c.group(2) != cur:
                funcs[cur].add(c.group(2))
    inside, todo = {root}, [root]
    while todo:
        for g in funcs.get(todo.pop(), ()):
            if g not in inside:
                inside.add(g)
                todo.append(g)
    entry = min(a for a, f in func_of.items() if f == root)

    blocks: dict[str, list[int]] = {}
    counts: collections.Counter = collections.Counter()
    ticks = 0
    in_tick = False
    this: list[str] = []
    worst: list[str] = []
    worst_n = 0
    pending: list[int] = []
    cur_block = None
    proc = subprocess.Popen(qemu, stdout=subprocess.PIPE, text=True, errors="replace")
    assert proc.stdout is not None
    for line in proc.stdout:
        if line.startswith("0x"):
            if cur_block is not None:
                pending.append(int(line[2:10], 16))
            continue
        if line.startswith("IN:"):
            cur_block = True
            pending = []
            continue
        if line.startswith("Trace"):
            # "Trace 0: <host code ptr> [cs_base/pc/flags/cflags] symbol": a block
            # is one translation (the host pointer), not one guest pc: icount
            # retranslates single-instruction blocks for I/O at the same pc.
            head, rest = line.split("[", 1)
            key = head.split()[-1]
            pc = int(rest.split("/")[1], 16)
            if pending:
                blocks[key] = pending
                pending = []
            cur_block = None
            f = func_of.get(pc & ~1, "")
            if pc == entry:
                in_tick = True
                ticks += 1
                this = []
            elif in_tick and f not in inside:
                in_tick = False
                n = sum(len(blocks.get(b, ())) for b in this)
                if n > worst_n:
                    worst_n, worst = n, this
            if in_tick:
                this.append(key)
                for a in blocks.get(key, ()):
                    counts[a] += 1
            continue
        if pending and not line.startswith("0x"):
            continue
    status = proc.wait()
    if ticks == 0:
        print("tick_profile: no tick executed", file=sys.stderr)
        return 2
    chains = symbolize(elf, sorted(counts))

    def table(cnt: collections.Counter, per: int, title: str) -> None:
        total = sum(cnt.values())
        by = collections.Counter()
        for a, n in cnt.items():
            by[component(chains.get(a, []), func_of.get(a, "?"))] += n
        print(f"{title}: {total / per:.0f} instructions")
        for name, n in by.most_common():
            print(f"  {n / per:7.0f}  {100 * n / total:5.1f} %  {name}")

    table(counts, ticks, f"mean control tick over the {ticks} ticks of the golden run")
    w = collections.Counter()
    for b in worst:
        for a in blocks.get(b, ()):
            w[a] += 1
    table(w, 1, "worst control tick of the golden run")
    cyc, divs = cycles(w, mnemonic)
    print(f"  estimated Cortex-M4 cycles of the worst tick: {cyc} ({divs} VDIV/VSQRT at 14 "
          f"cycles, loads 2, taken branches 3, UDIV/SDIV 12, code without wait states: "
          f"tick in CCM SRAM, callees from flash through the ART cache)")
    print(f"  = {100 * cyc / 17000:.1f} % of the 17 000 cycles of a 10 kHz tick at 170 MHz "
          f"(budget 40 %)")
    return 0 if status == 0 else 1


if __name__ == "__main__":
    sys.exit(main())

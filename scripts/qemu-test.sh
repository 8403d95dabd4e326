#!/usr/bin/env bash
# On-target test of the firmware core on QEMU's mps2-an386 (Cortex-M4F):
#  1. the golden vectors on the host (firmware/tests/golden.rs) are current;
#  2. the test image replays them bit for bit and stays within the tick budget
#     (exit status from semihosting; -icount shift=10 counts instructions);
#  3. the control tick's and the CAN receive side's call graphs reach no f64
#     soft-float and no panic, the image links no f64 routine at all, and a
#     deliberately bad build (feature bad-tick) is rejected by the same check;
#     the watchdog, fed by the core's policy, stays quiet in the replay, and an
#     image whose tick stops (feature watchdog-test) must end in its NMI;
#  4. where the tick's instructions go (tick_profile.py), and image sizes;
#  5. the B-G431B-ESC1 board image builds (no hardware here); its current
#     loop reaches no wait loop, its CAN receive side hands off through
#     `HandOff::accept`.
# Installs what it needs (apt qemu-system-arm, rustup target and llvm-tools).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
step() { printf '\n==> %s\n' "$*"; }

step "tools: qemu-system-arm, thumbv7em-none-eabihf, llvm-tools"
if ! command -v qemu-system-arm >/dev/null; then
    export DEBIAN_FRONTEND=noninteractive
    apt-get -o DPkg::Lock::Timeout=600 update -qq
    apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends qemu-system-arm >/dev/null
fi
if ! command -v addr2line >/dev/null; then
    DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends binutils >/dev/null
fi
rustup target add thumbv7em-none-eabihf >/dev/null
rustup component add llvm-tools >/dev/null
bin="$(rustc --print sysroot)/lib/rustlib/$(rustc -vV | sed -n 's/^host: //p')/bin"
objdump="$bin/llvm-objdump"
size="$bin/llvm-size"

step "golden vectors are current (host f32 results; f64 plan within 1 µm)"
# --workspace: the features of the workspace-wide test build, so its
# compiled dependencies are reused (-p alone would build another set).
cargo test --locked --workspace --test golden -- --nocapture 2>&1 | grep -E "golden|test result"

cd "$root/firmware/boards/qemu-mps2-an386"
# Board crates are their own workspaces: build each into its own target/,
# whatever CARGO_TARGET_DIR the caller set for the main workspace.
export CARGO_TARGET_DIR="$PWD/target"
elf=target/thumbv7em-none-eabihf/release/triquint-qemu-mps2-an386
step "QEMU image: fmt, clippy, build"
cargo fmt --check
cargo clippy --locked --release -- -D warnings
cargo build --locked --release

step "QEMU mps2-an386: golden replay and tick budget (exit status from the image)"
cargo run --locked --release | tee "$CARGO_TARGET_DIR/replay.log"

step "stack_check.py's bound holds on the replay: the two entry points' deepest use, measured"
# The image paints its stack and reads back the deepest word the replay
# wrote below its calls into the entry points; the static bound must not
# be below it (the same script bounds the ESC1 image's stack, below).
measured=$(sed -n 's/^stack: the entry points used at most \([0-9]*\) B.*/\1/p' "$CARGO_TARGET_DIR/replay.log")
bound=$(python3 "$root/scripts/stack_check.py" --memory-x memory.x \
    --thread triquint_can_rx --thread triquint_control_tick "$objdump" "$elf" |
    sed -n 's/^stack: worst \([0-9]*\) B.*/\1/p')
echo "measured $measured B, static bound $bound B"
if [ -z "$measured" ] || [ -z "$bound" ] || [ "$measured" -gt "$bound" ]; then
    echo "FAIL: the measured stack ($measured B) exceeds the static bound ($bound B), or one is missing" >&2
    exit 1
fi

step "QEMU mps2-an386: watchdog test (the tick stops; the watchdog's NMI must end the run)"
cargo build --locked --release --features watchdog-test 2>&1 | tail -1
if ! timeout 300 qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -icount shift=10 -kernel "$elf"; then
    echo "FAIL: the watchdog did not fire when the tick stopped" >&2
    exit 1
fi
cargo build --locked --release 2>&1 | tail -1

step "ELF check: tick (with the hand-off) and CAN receive side reach no f64 and no panic; no f64 in the image"
python3 "$root/scripts/elf_check.py" --no-double "$objdump" "$elf" triquint_control_tick triquint_can_rx

step "where the tick's instructions go (QEMU block trace)"
python3 "$root/scripts/tick_profile.py" "$objdump" "$elf" triquint_control_tick -- \
    qemu-system-arm -cpu cortex-m4 -machine mps2-an386 -nographic -monitor none -serial none \
    -semihosting-config enable=on,target=native -icount shift=10 \
    -d in_asm,exec,nochain -D /dev/stdout -kernel "$elf"

step "image size"
"$size" "$elf"

step "the ELF check rejects a deliberately bad tick (feature bad-tick)"
cargo build --locked --release --features bad-tick 2>&1 | tail -1
if python3 "$root/scripts/elf_check.py" --no-double "$objdump" "$elf" triquint_control_tick; then
    echo "FAIL: the check accepted a tick with an f64 operation and a panic path" >&2
    exit 1
fi
echo "ok: the bad build was rejected"
cargo build --locked --release 2>&1 | tail -1

step "B-G431B-ESC1 board image: fmt, clippy, build (flashing needs the board and probe-rs)"
cd "$root/firmware/boards/b-g431b-esc1"
export CARGO_TARGET_DIR="$PWD/target"
cargo fmt --check
cargo clippy --locked --release -- -D warnings
cargo build --locked --release
# The current loop (ADC1_2, raised when TIM1's injected conversions are done)
# waits on nothing; whatever runs the receive side on a frame (the CAN receive
# task, the hand-off draining the receive FIFO) hands the item over through
# the core's HandOff::accept (reserved slots, urgent items never dropped).
python3 "$root/scripts/elf_check.py" --self-test
# The panic, HardFault and default handlers turn the power stage off
# (TIM1's BDTR, halt.rs) before they wait for the watchdog.
python3 "$root/scripts/elf_check.py" --no-double --no-wait ADC1_2 --calls 'Receiver8on_frame=HandOff6accept' \
    --loads 'rust_begin_unwind=0x40012C44' --loads '^_HardFault$=0x40012C44' --loads '^DefaultHandler$=0x40012C44' \
    "$objdump" target/thumbv7em-none-eabihf/release/triquint-b-g431b-esc1
# The stack's worst case against the RAM the statics leave it: thread mode
# (the executor's tasks) plus one handler per priority level (main.rs: the
# current loop P0, the tick P1, embassy's CAN, EXTI and time-driver handlers
# P2), with 256 B to spare (docs/safety.md). The indirect calls are the
# executor's task polls and the waker vtables (every function whose address
# the image takes), and sequential-storage's `dyn Value`.
python3 "$root/scripts/stack_check.py" --self-test
python3 "$root/scripts/stack_check.py" --memory-x memory.x --margin 256 \
    --indirect 'Executor::run$=TaskStorage<F>::poll$|embassy_executor::raw::poll_exited$' \
    --indirect '^(EXTI9_5|FDCAN1_IT0|TIM1_BRK_TIM15|TIM6_DAC|_embassy_time_schedule_wake)$|TaskStorage<F>::poll$|CanRx::read_fd::|RxMode::on_interrupt$|Info::adjust_reference_counter$|channel::SendFuture<=embassy_executor::raw::waker::|FnOnce::call_once$|Interrupt::pend$' \
    --indirect 'map::store_item_inner::=sequential_storage::map::Value>::serialize_into$' \
    --thread Reset --level ADC1_2 --level TIM6_DAC --level FDCAN1_IT0,FDCAN1_IT1,EXTI9_5,TIM1_BRK_TIM15 \
    "$objdump" target/thumbv7em-none-eabihf/release/triquint-b-g431b-esc1
"$size" -A target/thumbv7em-none-eabihf/release/triquint-b-g431b-esc1 | grep -E "^(section|\.vector_table|\.text|\.rodata|\.ccmram_text|\.data|\.bss) "
# Flash left for what varies between machines: panic locations name source
# files by absolute path (the cargo registry, the target directory), so a
# longer CARGO_HOME or checkout path makes the same image larger.
esc1_flash_margin=1024
used=$("$size" -A target/thumbv7em-none-eabihf/release/triquint-b-g431b-esc1 |
    awk '$1 ~ /^\.(vector_table|text|rodata|ccmram_text|data)$/ { s += $2 } END { print s }')
region=$(sed -n 's/^ *FLASH *: *ORIGIN *= *[0-9a-fA-Fx]*, *LENGTH *= *\([0-9]*\)K.*/\1/p' memory.x)
left=$((region * 1024 - used))
echo "ESC1 flash: $used B of $((region * 1024)) ($left B left; at least $esc1_flash_margin required)"
if [ "$left" -lt "$esc1_flash_margin" ]; then
    echo "FAIL: the ESC1 image leaves $left B of flash, under $esc1_flash_margin B" >&2
    exit 1
fi

#!/usr/bin/env bash
# Regenerates the sample charts in docs/figures/ (shown in docs/charts.md and the README):
# for both paper cases, the plan overview, the 3-D platform path with its top
# and front views, and the simulation traces with and without feedforward.
# The SVGs come from `triquint plan/simulate --plot`; rsvg-convert turns them
# into PNG with DejaVu Sans, the font the charts were laid out with.
set -euo pipefail
cd "$(dirname "$0")/.."

need_apt=()
command -v rsvg-convert >/dev/null || need_apt+=(librsvg2-bin)
fc-list 2>/dev/null | grep -q "DejaVu Sans" || need_apt+=(fonts-dejavu-core)
if ((${#need_apt[@]})); then
    if [ "$(id -u)" = 0 ]; then
        apt-get update -qq && apt-get install -y -qq "${need_apt[@]}"
    else
        echo "figures.sh: needs ${need_apt[*]} (apt-get install as root)" >&2
        exit 1
    fi
fi

cargo build --release --locked -p triquint-host
bin="${CARGO_TARGET_DIR:-target}/release"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
out=docs/figures
mkdir -p "$out"

for c in 1 2; do
    d="$tmp/case$c"
    "$bin/triquint" plan "examples/paper-case$c.toml" -o "$d.json" --plot "$d" --quiet
    "$bin/triquint" simulate "$d.json" --plot "$d/sim" > /dev/null
    "$bin/triquint" simulate "$d.json" --no-feedforward --plot "$d/sim-noff" > /dev/null
    rsvg-convert "$d/overview.svg" -o "$out/case$c-plan-overview.png"
    rsvg-convert "$d/path3d.svg" -o "$out/case$c-path3d.png"
    rsvg-convert "$d/sim/overview.svg" -o "$out/case$c-sim.png"
    rsvg-convert "$d/sim-noff/overview.svg" -o "$out/case$c-sim-no-feedforward.png"
done
ls -l "$out"/*.png

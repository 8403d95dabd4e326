#!/usr/bin/env bash
# The main job: on a fresh machine with Rust, builds triquint, plans both of
# the paper's cases, verifies and reports them. Output goes to ./out/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p triquint-host -p triquint-sim
bin=target/release
mkdir -p out

for case in paper-case1 paper-case2; do
    echo "== $case: plan"
    $bin/triquint plan "examples/$case.toml" -o "out/$case.json" --plot "out/$case"
    echo "== $case: independent check"
    $bin/triquint check "out/$case.json" | tail -n 1
    echo "== $case: report (plots in out/$case/)"
    $bin/triquint report "out/$case.json"
done

echo
echo "max |jerk| (m/s³)      Case I   Case II"
echo "paper, as printed      3.102    2.808"
echo "paper's h, re-solved   1.054    2.661"
printf 'triquint               %.4f   %.4f\n' \
    "$(python3 -c 'import json,sys; print(max(json.load(open(sys.argv[1]))["max_abs"]["jerk"]))' out/paper-case1.json)" \
    "$(python3 -c 'import json,sys; print(max(json.load(open(sys.argv[1]))["max_abs"]["jerk"]))' out/paper-case2.json)"

#!/usr/bin/env bash
# The main job: on a fresh machine with Rust, builds triquint and runs the
# paper's cases. Output goes to ./out/.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked -p triquint-host -p triquint-sim
bin=target/release
mkdir -p out

echo "== Inverse kinematics of the paper's via-points (Tables 2 and 6)"
for p in "-90 90 680" "-60 60 620" "90 -90 680" "-86 83.66 597.66" "0 -84.85 515.15"; do
    # shellcheck disable=SC2086
    $bin/triquint ik $p
done
echo "== Forward kinematics back from Table 2, P1"
$bin/triquint fk 376.68 244.16 336.13

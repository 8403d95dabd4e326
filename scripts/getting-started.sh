#!/usr/bin/env bash
# Runs the README's five-minute tutorial and docs/getting-started.md's
# `sh tutorial` blocks, as written, in a fresh clone of this repository's
# HEAD: from `cargo install --path host` to a simulated run.
#
# `cargo install --path …` runs in this checkout with its target directory
# (CI has just built the release binaries there, so it takes seconds), into
# a prefix of its own; the other commands run in the clone, with only that
# prefix's binaries on PATH. GETTING_STARTED_FRESH_BUILD=1 builds in the
# clone instead, from nothing (many minutes).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    git clone --quiet "$root" "$work/triquint"
else
    # Not a git checkout (an unpacked archive): its files, without builds.
    mkdir "$work/triquint"
    tar -C "$root" --exclude=./target --exclude=./out -cf - . | tar -C "$work/triquint" -xf -
fi
prefix="$work/prefix"
mkdir -p "$prefix/bin"

# The blocks, in order: README first, then the guide.
extract() {
    awk '/^```sh tutorial$/ {on = 1; next} /^```/ {on = 0} on' "$1"
}
script="$work/tutorial.sh"
for page in README.md docs/getting-started.md; do
    block="$(extract "$work/triquint/$page")"
    [ -n "$block" ] || { echo "getting-started: no \`sh tutorial\` block in $page" >&2; exit 1; }
    printf '# %s\n%s\n' "$page" "$block"
done > "$script"

# `cargo install --path DIR`: in this checkout (see above), or in the clone.
cargo() {
    if [ "$1" = install ]; then
        if [ "${GETTING_STARTED_FRESH_BUILD:-0}" = 1 ]; then
            command cargo "$@" --locked --root "$prefix" --target-dir "$work/target"
        else
            (cd "$root" && command cargo "$@" --locked --root "$prefix")
        fi
    else
        command cargo "$@"
    fi
}
export -f cargo
export root prefix work

cd "$work/triquint"
echo "== running $(grep -cv '^#' "$script") lines of tutorial in a fresh clone"
PATH="$prefix/bin:$PATH" bash -euo pipefail -x "$script"
# What the tutorial says it makes.
for f in case1.json case1-plot/overview.svg case1-sim/overview.svg my-plan.json mine.json; do
    [ -s "$f" ] || { echo "getting-started: $f was not written" >&2; exit 1; }
done
echo "== getting started: every command ran"

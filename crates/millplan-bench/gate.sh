#!/usr/bin/env bash
# The benchmark gate: builds `millplan` and the gate's runner in release (the
# counts are those of the binary users run), then runs the reduced
# workloads under valgrind (cachegrind, one thread) and compares each
# instruction count with crates/millplan-bench/gate-baseline.toml.
#   gate.sh                 compare; exit 1 when a count is > 3 % above its baseline
#   gate.sh --update        rewrite the baseline (commit it, saying why)
#   gate.sh --only speed,post   some workloads only
set -euo pipefail
cd "$(dirname "$0")/../.."
if ! command -v valgrind >/dev/null 2>&1; then
  echo "gate: valgrind not found (apt-get install valgrind)" >&2
  exit 2
fi
cargo build --quiet --release -p millplan --bin millplan -p millplan-bench --bin gate
target=${CARGO_TARGET_DIR:-target}
made_with="$(rustc -V | cut -d' ' -f1-2), $(valgrind --version)"
exec "$target/release/gate" --millplan "$target/release/millplan" --made-with "$made_with" "$@"

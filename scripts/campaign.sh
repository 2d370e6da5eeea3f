#!/usr/bin/env bash
# The randomized property campaign (CONTRIBUTING.md): rounds of fresh cases
# until MINUTES have passed (default 30), CASES per property each round
# (default 20000, about three minutes on two cores). Stops at the first
# failure; its counterexample is then in tests/suite/NAME.proptest-regressions,
# to fix and commit with a comment. Usage:
#   scripts/campaign.sh [MINUTES] [CASES]
set -eu
cd "$(dirname "$0")/.."
minutes=${1:-30}
cases=${2:-20000}
case "$minutes$cases" in
    *[!0-9]*|"") echo "campaign: MINUTES and CASES are whole numbers" >&2; exit 2 ;;
esac
cargo test --release --test suite --no-run
end=$(($(date +%s) + 60 * minutes))
round=0
while [ "$(date +%s)" -lt "$end" ]; do
    round=$((round + 1))
    echo "== round $round: $cases cases per property"
    RAYTERM_CAMPAIGN=$cases cargo test --release --test suite -q -- properties:: fuzz_loaders::
done
echo "campaign: $round rounds of $cases cases per property, no failure"

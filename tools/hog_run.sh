#!/usr/bin/env bash
# The README's test command beside 8 busy processes on the cores (issue 34): no test may
# depend on the machine's speed. Run from the repository root with its .venv; prints pytest's
# summary and the exit status. The hogs are this script's children, ended by their ids.
set -uo pipefail
cd "$(dirname "$0")/.."
hogs=()
for _ in 1 2 3 4 5 6 7 8; do
  bash -c 'while :; do :; done' &
  hogs+=("$!")
done
end_hogs() { kill "${hogs[@]}" 2>/dev/null || true; }
trap end_hogs EXIT
start=$(date +%s)
status=0
.venv/bin/python -m pytest -q "$@" || status=$?
end_hogs
echo "default run beside 8 busy processes: pytest exit status ${status} in $(( $(date +%s) - start )) s"
exit "$status"

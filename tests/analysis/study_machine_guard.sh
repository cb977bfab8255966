#!/bin/sh
# scripts/study keeps earlier results only where they are this machine's: a folder holding a
# file of another machine stops it at once, with one line naming both, before any step runs.
# Usage (from the source root, CONTACTLAB_STUDY_BUILD set): study_machine_guard.sh DIR
set -u
dir=$1
rm -rf "$dir" && mkdir -p "$dir" || exit 1
printf '%s\n' '{"context": {"machine": {"cpu_model": "Another CPU", "cores": 64}}}' >"$dir/old.json"
if scripts/study --quick --out "$dir" >"$dir.log" 2>&1; then
  echo "study ran over a folder of another machine's results"; cat "$dir.log"; exit 1
fi
grep -q "old.json was measured on 'Another CPU' (64 cores), this machine is" "$dir.log" &&
  grep -q -- "--force measures every step here" "$dir.log" ||
  { echo "no line naming both machines:"; cat "$dir.log"; exit 1; }
[ ! -e "$dir/tuning" ] || { echo "a step ran before the check"; exit 1; }
[ "$(cat "$dir/old.json")" = '{"context": {"machine": {"cpu_model": "Another CPU", "cores": 64}}}' ] ||
  { echo "the kept file changed"; exit 1; }
echo ok

#!/bin/sh
# scripts/machine-slug names a folder from the machine a result file records (what the study
# uses), which can differ from /proc/cpuinfo's name for the same VM; a file without that
# description is one line and a non-zero exit.
# Usage (from the source root): machine_slug.sh SCRATCH_DIR
set -u
dir=$1
rm -rf "$dir" && mkdir -p "$dir" || exit 1
check() {  # EXPECTED ARGS...
  expected=$1; shift
  got=$(scripts/machine-slug "$@") || { echo "machine-slug $*: failed"; exit 1; }
  [ "$got" = "$expected" ] || { echo "machine-slug $*: '$got', expected '$expected'"; exit 1; }
}
printf '%s\n' '{"context": {"machine": {"cpu_model": "Oxide Virtual Turin-like Processor", "cores": 2}}}' >"$dir/r.json"
check oxide-virtual-turin-like-processor-2c --context "$dir/r.json"
printf '%s\n' '{"context": {"machine": {"cpu_model": " Intel(R) Xeon(R) Processor ", "cores": 16}}}' >"$dir/x.json"
check intel-r-xeon-r-processor-16c --context "$dir/x.json"
# The same VM's /proc/cpuinfo: one socket, two cores.
printf 'processor\t: 0\nmodel name\t: AMD EPYC\nphysical id\t: 0\ncore id\t\t: 0\n\nprocessor\t: 1\nmodel name\t: AMD EPYC\nphysical id\t: 0\ncore id\t\t: 1\n' >"$dir/cpuinfo"
check amd-epyc-2c "$dir/cpuinfo"
for bad in '{}' '{"context": {"machine": {"cpu_model": "", "cores": 2}}}' 'not json'; do
  printf '%s\n' "$bad" >"$dir/bad.json"
  if scripts/machine-slug --context "$dir/bad.json" >"$dir/out" 2>"$dir/err"; then
    echo "machine-slug accepted $bad"; exit 1
  fi
  [ "$(wc -l <"$dir/err")" = 1 ] && grep -q "bad.json" "$dir/err" ||
    { echo "not one line naming the file for $bad:"; cat "$dir/err"; exit 1; }
done
echo ok

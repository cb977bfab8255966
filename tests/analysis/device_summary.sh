#!/bin/sh
# analysis/device_summary.py over the committed 16-core folder: its speed-up table holds the
# measured Table 7 speed-up at 16 threads, the emulation table marks emulated values and gives
# their error (the unsorted particle loop's +76 %; +61 % against the later sweeps), an emulation priced by bytes gives the
# bandwidth each measured loop drew, and a folder without result files is one line and a
# non-zero exit.
set -eu
out=$1
rm -rf "$out" && mkdir -p "$out"
folder=results/intel-r-xeon-r-processor-16c
/usr/bin/python3 analysis/device_summary.py "$folder" --out "$out/summary.md" \
  --emulation results/amd-epyc-2c/emulation-threads.json > /dev/null
grep -q '| `particle/sorted/full/static,200` | 0.2868 (1.00) |.*| 0.0270 (10.61) |' "$out/summary.md"
grep -q '| `particle/unsorted/full/static` | 16 | 8.63 | \*15.18\*† | +76 % |' "$out/summary.md"
# ... and beside the later sweeps (detection-16-*.json, 7f43f66), with the error against them.
grep -q '| `particle/unsorted/full/static` | 16 | 8.63 | \*15.18\*† | +76 % | 9.44 | +61 % |' "$out/summary.md"
grep -q '| 16,384,000 | `particle/sorted/full/static,200` | 16 |' "$out/summary.md"
# An emulation priced by bytes: the loop's bytes over the loop measured there (the unsorted
# particle loop drew 92.7 GB/s at 16 threads by that count), beside the emulation's curve.
/usr/bin/python3 analysis/device_summary.py "$folder" --out "$out/bandwidth.md" \
  --emulation results/oxide-virtual-turin-like-processor-2c/emulation-threads-bandwidth.json > /dev/null
grep -q '| `particle/unsorted/full/static` | 16 | 33.70 | 92.7 | \*229.8\*† |' "$out/bandwidth.md"
# The tuner's 16-thread choice predicted on a 2-core VM, against the chunk study's rounds: the
# chunk it chose (512) was not measured, so the study's chunks around it are given.
/usr/bin/python3 analysis/device_summary.py "$folder" --out "$out/tune.md" \
  --tune results/oxide-virtual-turin-like-processor-2c/tune-predict-16-paper.json > /dev/null
grep -q "| model's choice | \`particle/sorted/full/dynamic,512\` | \*0.0060\*† | not measured; \`dynamic,256\` +45%, \`dynamic,1024\` +14% |" "$out/tune.md"
grep -q "| a structure's best | \`particle/sorted/half/dynamic,256\` | \*0.0090\*† | +89% |" "$out/tune.md"
# A sweep that recorded T_s's parts (samples.parts_s) gets their table; the 16-core files,
# from before them, get none.
/usr/bin/python3 analysis/device_summary.py tests/analysis/fixture/parts-2c --out "$out/parts.md" > /dev/null
grep -q "^T_s's parts" "$out/parts.md"
grep -q '| `particle/sorted/half/static` | reorder | 0\.[0-9]* (1\.00) | 0\.[0-9]* ([0-9.]*) |' "$out/parts.md"
# ... and a folder's machine file its triad and arithmetic table.
grep -q '^| arithmetic, of P x 1 thread | 1.00 | [0-9.]* |$' "$out/parts.md"
grep -q '^| triad, 64 MiB \[GB/s\] | [0-9.]* | [0-9.]* |$' "$out/parts.md"
if grep -q "^T_s's parts" "$out/summary.md"; then
  echo "a parts table from files without parts" >&2
  exit 1
fi
mkdir -p "$out/empty"
if /usr/bin/python3 analysis/device_summary.py "$out/empty" 2> "$out/err.txt"; then
  echo "an empty folder was summarised" >&2
  exit 1
fi
[ "$(wc -l < "$out/err.txt")" -eq 1 ] && grep -q "no result file" "$out/err.txt"
echo ok

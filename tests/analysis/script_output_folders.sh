#!/bin/sh
# The scripts' output folders (scripts/output_folder.py, the study's make_folder): made at the
# start as mkdir -p would, before any run; a folder that cannot be made (a file in the way) stops
# the script there with one line naming it, exit 2, and the file untouched.
# Usage (from the source root, CONTACTLAB_STUDY_BUILD set): script_output_folders.sh DIR
set -u
dir=$1
rm -rf "$dir" && mkdir -p "$dir" || exit 1
export TMPDIR="$dir"  # the Python scripts' work folders, left behind by the failed runs below
B=$CONTACTLAB_STUDY_BUILD/contactlab
blocker=$dir/blocker
printf 'kept\n' >"$blocker"
status=0

# expect_blocked NAME COMMAND...: exit 2, nothing on stdout, one line on stderr naming the file.
expect_blocked() {
  name=$1
  shift
  "$@" >"$dir/$name.out" 2>"$dir/$name.err"
  rc=$?
  if [ $rc != 2 ] || [ -s "$dir/$name.out" ] || [ "$(wc -l <"$dir/$name.err")" != 1 ] ||
    ! grep -q "'$blocker' is a file, not a folder" "$dir/$name.err"; then
    echo "$name: expected exit 2 and one line naming $blocker; got exit $rc:"
    cat "$dir/$name.out" "$dir/$name.err"
    status=1
  fi
  [ "$(cat "$blocker")" = kept ] || { echo "$name: the file in the way changed"; status=1; }
}

# expect_made NAME FOLDER COMMAND...: FOLDER exists after COMMAND (which may fail later on).
expect_made() {
  name=$1 folder=$2
  shift 2
  "$@" >"$dir/$name.out" 2>&1
  [ -d "$folder" ] || { echo "$name: $folder was not made"; cat "$dir/$name.out"; status=1; }
}

py=/usr/bin/python3
expect_blocked study scripts/study --quick --out "$blocker/a/b"
expect_blocked beverloo $py scripts/beverloo --quick --contactlab "$B" --out "$blocker/a/b"
expect_blocked retune-study $py scripts/retune-study --quick --contactlab "$B" --out "$blocker/a/b"
# /bin/false as the programs: had a run started, the script would fail otherwise.
expect_blocked detect-compare $py scripts/detect-compare /bin/false /bin/false \
  --scene "s=$blocker:0.05" --variant particle/sorted/full/static --json "$blocker/a/b/c.json"
expect_blocked bench-compare $py scripts/bench-compare /bin/false /bin/false --json "$blocker/a/c.json"
expect_blocked large-scenes $py scripts/large-scenes --contactlab /bin/false --json "$blocker/a/c.json"
expect_blocked dem-isa-compare $py scripts/dem-isa-compare --run a=/bin/false \
  --config experiments/dem/drop-box.json --restart "$blocker" --json "$blocker/a/c.json"

# Made at the start: the DEM studies' folders before their first run (which /bin/false fails),
# detect-compare's --json folder with a run of two detections.
expect_made beverloo-made "$dir/bev/a/b" $py scripts/beverloo --quick --contactlab /bin/false \
  --out "$dir/bev/a/b"
expect_made large-scenes-made "$dir/large/a" $py scripts/large-scenes --contactlab /bin/false \
  --json "$dir/large/a/b.json"
expect_made retune-made "$dir/ret/a/b" $py scripts/retune-study --quick --contactlab /bin/false \
  --out "$dir/ret/a/b"
"$B" scene --kind uniform --n 500 -D 0.05 --out "$dir/s.bin" >/dev/null || exit 1
$py scripts/detect-compare "$B" "$B" --scene "s=$dir/s.bin:0.05" \
  --variant particle/sorted/full/static --threads 1 --rounds 1 --repeat 1 \
  --json "$dir/cmp/a/b/c.json" >"$dir/detect-compare-made.out" 2>&1 ||
  { echo "detect-compare failed:"; cat "$dir/detect-compare-made.out"; status=1; }
[ -f "$dir/cmp/a/b/c.json" ] || { echo "detect-compare wrote no $dir/cmp/a/b/c.json"; status=1; }
grep -q '"git_commit"' "$dir/cmp/a/b/c.json" 2>/dev/null ||
  { echo "detect-compare recorded no build commit in $dir/cmp/a/b/c.json"; status=1; }
# dem-isa-compare: the --json folder made, and a record naming the set each run's step ran on.
"$B" dem run experiments/dem/drop-box.json --steps 20 --checkpoint "$dir/drop.chk" \
  >"$dir/drop.out" 2>&1 || { echo "dem run failed:"; cat "$dir/drop.out"; status=1; }
$py scripts/dem-isa-compare --run best="$B" --run baseline="$B:SSE4" \
  --config experiments/dem/drop-box.json --restart "$dir/drop.chk" --steps 5 --rounds 1 \
  --json "$dir/isa/a/b/c.json" >"$dir/dem-isa-compare-made.out" 2>&1 ||
  { echo "dem-isa-compare failed:"; cat "$dir/dem-isa-compare-made.out"; status=1; }
grep -q '"step_isa": "baseline"' "$dir/isa/a/b/c.json" 2>/dev/null ||
  { echo "dem-isa-compare wrote no record of the baseline run in $dir/isa/a/b/c.json"; status=1; }
# Side by side (two CPUs: every machine here has them; a one-CPU one is refused by name).
if [ "$(nproc)" -ge 2 ]; then
  $py scripts/dem-isa-compare --run best="$B" --run baseline="$B:SSE4" --side-by-side \
    --config experiments/dem/drop-box.json --restart "$dir/drop.chk" --steps 5 --rounds 2 \
    --json "$dir/isa/side.json" >"$dir/dem-isa-side.out" 2>&1 ||
    { echo "dem-isa-compare --side-by-side failed:"; cat "$dir/dem-isa-side.out"; status=1; }
  grep -q '"method": "both runs at once' "$dir/isa/side.json" 2>/dev/null ||
    { echo "dem-isa-compare --side-by-side recorded no side-by-side method"; status=1; }
fi
# One run side by side with nothing: refused in one line that says what it needs.
$py scripts/dem-isa-compare --run a="$B" --side-by-side --config experiments/dem/drop-box.json \
  --restart "$dir/drop.chk" >"$dir/side-one.out" 2>"$dir/side-one.err"
rc=$?
if [ $rc = 0 ] || [ "$(wc -l <"$dir/side-one.err")" != 1 ] ||
  ! grep -q "side-by-side needs two runs" "$dir/side-one.err"; then
  echo "dem-isa-compare --side-by-side with one run: expected a one-line refusal; got exit $rc:"
  cat "$dir/side-one.err"
  status=1
fi

[ $status = 0 ] && echo ok
exit $status

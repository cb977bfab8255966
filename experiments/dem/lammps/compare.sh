#!/bin/sh
# Interleaved timing of contactlab's DEM step and LAMMPS gran/hooke/history on the same settled
# bed, at 1 and 2 threads/ranks, ROUNDS times. Needs: contactlab built (Release), lmp and mpirun
# (Debian: apt-get install lammps), the bed's checkpoint and its last frame:
#   compare.sh BUILD_DIR CHECKPOINT FRAME.vtp [ROUNDS] [THREAD_COUNTS] [SETS]
# THREAD_COUNTS default "1 2". SETS: the instruction sets contactlab's step runs on, each timed in
# every round (CONTACTLAB_SIMD; default "best": the CPU's best; e.g. "best AVX2 SSE4" for
# AVX-512, AVX2 and the baseline, docs/dem.md "One binary").
# Prints one line per run: code, threads, particle-steps/s.
set -eu
build=$1 checkpoint=$2 frame=$3 rounds=${4:-2} thread_counts=${5:-1 2} sets=${6:-best}
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
work=$(mktemp -d)
cp "$here/in.bench-data" "$here/params.lmp" "$work/"
python3 "$here/vtp_to_data.py" "$frame" "$work/data.bed" > /dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_WAIT_POLICY=passive
lammps_rate() {  # $1: log; the second loop is the timed one
  awk '/^Loop time/ {t = $4; n = $(NF-1); s = $9} END {printf "%.4g\n", n * s / t}' "$1"
}
for round in $(seq "$rounds"); do
  for threads in $thread_counts; do
    for set in $sets; do
      CONTACTLAB_SIMD=$set CONTACTLAB_DEM_BENCH_CONFIG="$repo/experiments/dem/settle-bed.json" \
      CONTACTLAB_DEM_BENCH_CHECKPOINT="$checkpoint" \
        "$build/kernels/dem/contactlab_dem_benchmark" --benchmark_filter="BM_DemStep/threads:$threads/" \
        --benchmark_min_time=10 --benchmark_format=csv 2>/dev/null |
        awk -F, -v r="$round" -v t="$threads" -v s="$set" \
          '/BM_DemStep/ {print "round " r ": contactlab " s " threads " t ": " $0}'
    done
    (cd "$work" && OMP_NUM_THREADS=1 mpirun -np "$threads" lmp -nocite -in in.bench-data \
       -log "lmp$threads.log" -screen none)
    echo "round $round: lammps ranks $threads: $(lammps_rate "$work/lmp$threads.log") particle-steps/s"
    grep -A7 "MPI task timing breakdown" "$work/lmp$threads.log" | tail -6 | sed "s/^/  lammps $threads: /"
  done
done
rm -rf "$work"

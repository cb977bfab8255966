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
# OpenMP's wait policy stays libgomp's default, what a user's run gets: `passive` made each of
# contactlab's threads sleep at every barrier (about 40 us a step more at two threads on a Xeon
# VM), and LAMMPS's ranks run no OpenMP.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
unset OMP_WAIT_POLICY
lammps_rate() {  # $1: log; the second loop is the timed one
  awk '/^Loop time/ {t = $4; n = $(NF-1); s = $9} END {printf "%.4g\n", n * s / t}' "$1"
}
contactlab_run() {  # $1: round, $2: set, $3: threads
  CONTACTLAB_SIMD=$2 CONTACTLAB_DEM_BENCH_CONFIG="$repo/experiments/dem/settle-bed.json" \
  CONTACTLAB_DEM_BENCH_CHECKPOINT="$checkpoint" \
    "$build/kernels/dem/contactlab_dem_benchmark" --benchmark_filter="BM_DemStep/threads:$3/" \
    --benchmark_min_time=10 --benchmark_format=csv 2>/dev/null |
    awk -F, -v r="$1" -v t="$3" -v s="$2" \
      '/BM_DemStep/ {print "round " r ": contactlab " s " threads " t ": " $0}'
}
lammps_run() {  # $1: round, $2: ranks
  (cd "$work" && OMP_NUM_THREADS=1 mpirun -np "$2" lmp -nocite -in in.bench-data \
     -log "lmp$2.log" -screen none)
  echo "round $1: lammps ranks $2: $(lammps_rate "$work/lmp$2.log") particle-steps/s"
  grep -A7 "MPI task timing breakdown" "$work/lmp$2.log" | tail -6 | sed "s/^/  lammps $2: /"
}
# Each ratio is taken between runs next to each other in time: this VM's speed drifts by up to
# 1.3x over half a minute. Within a round the thread counts zigzag: the first runs the other sets,
# LAMMPS, then the first set; the next runs the first set, LAMMPS, then the others; and so on. So
# the first set at one thread count runs right before it at the next (the scaling), and each
# thread count's first set and LAMMPS are neighbours (the ratio).
first=${sets%% *}
others=$(printf '%s\n' $sets | sed 1d | tac | tr '\n' ' ')
for round in $(seq "$rounds"); do
  forward=1
  for threads in $thread_counts; do
    if [ "$forward" = 1 ]; then
      for set in $others; do contactlab_run "$round" "$set" "$threads"; done
      lammps_run "$round" "$threads"
      contactlab_run "$round" "$first" "$threads"
      forward=0
    else
      contactlab_run "$round" "$first" "$threads"
      lammps_run "$round" "$threads"
      for set in $(printf '%s\n' $others | tac); do contactlab_run "$round" "$set" "$threads"; done
      forward=1
    fi
  done
done
rm -rf "$work"

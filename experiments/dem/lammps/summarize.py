#!/usr/bin/env python3
"""compare.sh's output as a result file: each run's particle-steps/s per round, the median of the
per-round ratios to LAMMPS (with their smallest and largest), and where the step's time goes
(contactlab's phase shares from the benchmark's counters, LAMMPS's timing breakdown).

  compare.sh BUILD BED.chk FRAME.vtp 5 1 "best AVX2 SSE4" > out.txt
  summarize.py out.txt --commit C --build "Release -march=native" --json results/M/dem-vs-lammps.json

Machine fields come from /proc/cpuinfo and os.cpu_count(), the date from the clock. A malformed
line, or a round without LAMMPS, is one line on stderr and exit 1; the JSON is written to a
temporary file and renamed, so a failed run leaves an earlier file as it was.
"""
import argparse
import csv
import datetime
import json
import os
import re
import statistics
import sys
import tempfile

# Google Benchmark's CSV: name, iterations, real_time, cpu_time, time_unit, bytes_per_second,
# items_per_second, label, error_occurred, error_message, then the counters by name.
# (Google Benchmark orders them by name.) Benchmarks since the near pairs (8bd78c4) add two.
COUNTERS = ["contacts_per_particle", "max_span", "pairs_per_particle", "particle_steps_per_s",
            "share_integration", "share_neighbor", "share_pair_forces", "share_reduction",
            "share_update"]
NEAR_COUNTERS = sorted(COUNTERS + ["near_pairs_per_particle", "steps_per_near_build"])
LAYOUTS = {10 + len(c): c for c in (COUNTERS, NEAR_COUNTERS)}
RUN = re.compile(r'^round (\d+): contactlab (\S+) threads (\d+): (.*)$')
LAMMPS = re.compile(r'^round (\d+): lammps ranks (\d+): ([0-9.eE+-]+) particle-steps/s$')
SECTION = re.compile(r'^\s+lammps (\d+): (\w+)\s*\|.*\|\s*([0-9.]+)\s*$')


def fail(message):
    sys.exit(f"summarize.py: {message}")


def parse(lines):
    runs, breakdown = {}, {}
    for number, line in enumerate(lines, 1):
        line = line.rstrip("\n")
        if m := RUN.match(line):
            fields = next(csv.reader([m.group(4)]))
            if len(fields) not in LAYOUTS:
                fail(f"line {number}: {len(fields)} CSV fields, expected one of "
                     f"{sorted(LAYOUTS)}")
            counters = dict(zip(LAYOUTS[len(fields)], map(float, fields[10:])))
            key = (f"contactlab {m.group(2)}", int(m.group(3)))
            runs.setdefault(key, {"label": fields[7], "rounds": {}, "shares": [], "near": []})
            runs[key]["rounds"][int(m.group(1))] = counters["particle_steps_per_s"]
            runs[key]["shares"].append({k[6:]: v for k, v in counters.items()
                                        if k.startswith("share_")})
            if "near_pairs_per_particle" in counters:
                runs[key]["near"].append({k: counters[k] for k in (
                    "pairs_per_particle", "near_pairs_per_particle", "steps_per_near_build")})
        elif m := LAMMPS.match(line):
            key = ("LAMMPS", int(m.group(2)))
            runs.setdefault(key, {"label": f"lmp {m.group(2)} rank(s)", "rounds": {}})
            runs[key]["rounds"][int(m.group(1))] = float(m.group(3))
        elif m := SECTION.match(line):
            breakdown.setdefault(int(m.group(1)), {}).setdefault(m.group(2), []).append(
                float(m.group(3)) / 100.0)
        elif line.strip() and "-----" not in line:
            fail(f"line {number}: not a line compare.sh writes: {line[:60]}")
    return runs, breakdown


def summarize(runs, breakdown):
    out = {}
    for (name, threads), run in sorted(runs.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        lammps = runs.get(("LAMMPS", threads))
        if lammps is None:
            fail(f"no LAMMPS run at {threads} rank(s) to compare {name} with")
        missing = set(run["rounds"]) - set(lammps["rounds"])
        if missing:
            fail(f"round {min(missing)} has {name} at {threads} thread(s) but no LAMMPS")
        ratios = [run["rounds"][r] / lammps["rounds"][r] for r in sorted(run["rounds"])]
        entry = {
            "label": run["label"],
            "threads": threads,
            "rounds": [run["rounds"][r] for r in sorted(run["rounds"])],
            "median": statistics.median(run["rounds"].values()),
            "ratio_to_lammps_median": statistics.median(ratios),
            "min": min(ratios),
            "max": max(ratios),
        }
        fewest = min(t for (n, t) in runs if n == name)
        if threads > fewest:
            # The criterion is per round: this many threads over the fewest, in the
            # same round (compare.sh runs the two next to each other).
            base = runs[(name, fewest)]["rounds"]
            scaling = [run["rounds"][r] / base[r] for r in sorted(run["rounds"]) if r in base]
            if scaling:
                entry["over_fewest_threads"] = {
                    "threads": fewest, "rounds": scaling,
                    "median": statistics.median(scaling), "min": min(scaling),
                    "max": max(scaling)}
        if "shares" in run:
            entry["phase_shares_median"] = {
                k: statistics.median(s[k] for s in run["shares"]) for k in run["shares"][0]}
        if run.get("near"):
            entry["near_pairs_median"] = {
                k: statistics.median(s[k] for s in run["near"]) for k in run["near"][0]}
        else:
            entry["timing_breakdown_median"] = {
                k: statistics.median(v) for k, v in breakdown.get(threads, {}).items()}
        out[f"{name} {threads}"] = entry
    return out


def machine():
    model = "unknown"
    flags = ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name") and model == "unknown":
                    model = line.split(":", 1)[1].strip()
                if line.startswith("flags") and not flags:
                    flags = line.split(":", 1)[1]
    except OSError:
        pass
    return {"proc_cpuinfo_model": model, "cores": os.cpu_count(),
            "avx512f": " avx512f" in f" {flags}", "avx2": " avx2" in f" {flags}"}


def self_test():
    sample = [
        'round 1: contactlab best threads 1: "BM_DemStep/threads:1/real_time",2100,5.2,5.2,ms,,,'
        '"step on AVX-512",,,4.4,5122,3.75,1.2e+07,0.08,0.02,0.77,0.004,0.13',
        "round 1: lammps ranks 1: 6e+06 particle-steps/s",
        "  lammps 1: ---------------------------------------------------------------",
        "  lammps 1: Pair    | 20.52      | 20.52      | 20.52      |   0.0 | 80.00",
        "  lammps 1: Modify  | 2.693      | 2.693      | 2.693      |   0.0 | 15.00",
        'round 2: contactlab best threads 1: "BM_DemStep/threads:1/real_time",2100,5.2,5.2,ms,,,'
        '"step on AVX-512",,,4.4,5122,3.75,1.5e+07,0.08,0.02,0.77,0.004,0.13',
        "round 2: lammps ranks 1: 5e+06 particle-steps/s",
        'round 1: contactlab best threads 2: "BM_DemStep/threads:2/real_time",2100,5.2,5.2,ms,,,'
        '"step on AVX-512",,,4.4,5122,3.75,2.4e+07,0.08,0.02,0.77,0.004,0.13',
        "round 1: lammps ranks 2: 1e+07 particle-steps/s",
        # A benchmark with the near pairs' two counters (names in order: near_pairs_... after
        # max_span, steps_per_near_build last).
        'round 1: contactlab AVX2 threads 1: "BM_DemStep/threads:1/real_time",2100,5.2,5.2,ms,,,'
        '"step on AVX2",,,4.4,5122,2.7,3.75,9e+06,0.08,0.05,0.7,0.004,0.17,36',
    ]
    result = summarize(*parse(sample))
    best = result["contactlab best 1"]
    assert best["rounds"] == [1.2e7, 1.5e7], best
    assert abs(best["ratio_to_lammps_median"] - 2.5) < 1e-12, best  # median of 2.0 and 3.0
    assert (best["min"], best["max"]) == (2.0, 3.0), best
    assert abs(best["phase_shares_median"]["pair_forces"] - 0.77) < 1e-12, best
    assert result["LAMMPS 1"]["timing_breakdown_median"] == {"Pair": 0.8, "Modify": 0.15}
    two = result["contactlab best 2"]
    assert two["over_fewest_threads"]["rounds"] == [2.0], two  # round 1 only: 2.4e7 / 1.2e7
    assert "over_fewest_threads" not in best, best
    assert "near_pairs_median" not in best, best
    avx2 = result["contactlab AVX2 1"]
    assert avx2["rounds"] == [9e6], avx2
    assert avx2["near_pairs_median"] == {"pairs_per_particle": 3.75,
                                         "near_pairs_per_particle": 2.7,
                                         "steps_per_near_build": 36.0}, avx2
    try:
        summarize(*parse(sample[:1]))
    except SystemExit as e:
        assert "no LAMMPS run" in str(e), e
    else:
        raise AssertionError("a run without LAMMPS was accepted")
    print("summarize.py: self-test passed")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", nargs="?", help="compare.sh's output")
    parser.add_argument("--commit", default="unknown")
    parser.add_argument("--build", default="unknown")
    parser.add_argument("--note", default="")
    parser.add_argument("--json")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    if not args.output:
        fail("give compare.sh's output file (or --self-test)")
    try:
        with open(args.output) as f:
            runs, breakdown = parse(f.readlines())
    except OSError as e:
        fail(f"{args.output}: {e.strerror}")
    document = {
        "kind": "contactlab-dem-vs-lammps",
        "machine": machine(),
        "date": datetime.date.today().isoformat(),
        "commit": args.commit,
        "build": args.build,
        "method": "experiments/dem/lammps/compare.sh (interleaved rounds: each round runs every "
                  "set and LAMMPS once, each ratio's two runs next to each other); ratio = median "
                  "over rounds of the round's ratio to LAMMPS, with the smallest and largest; "
                  "over_fewest_threads: the per-round ratio to the same set at the fewest "
                  "threads; shares: contactlab_dem_benchmark's "
                  "phase shares, LAMMPS's MPI task timing breakdown (%total / 100)",
        "note": args.note,
        "runs": summarize(runs, breakdown),
    }
    text = json.dumps(document, indent=1) + "\n"
    if not args.json:
        sys.stdout.write(text)
        return
    folder = os.path.dirname(os.path.abspath(args.json))
    os.makedirs(folder, exist_ok=True)
    with tempfile.NamedTemporaryFile("w", dir=folder, delete=False, suffix=".tmp") as f:
        f.write(text)
    os.replace(f.name, args.json)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The detection measured on a machine of many cores (scripts/device-16core), as one page.

  analysis/device_summary.py RESULTS_DIR [--out RESULTS_DIR/summary.md]
                             [--emulation OTHER_MACHINE/emulation-threads.json ...]
                             [--tune OTHER_MACHINE/tune.json ...]

Reads, where present: detection-16-sorted.json and detection-16-paper.json (sweeps at 1-16
threads), chunk-study-16.json, large-scenes/*.json (detect at 1 and 16 threads on larger scenes)
and at-<commit>/paper-tables-16.json (an earlier commit's sweep, for the change). Writes speed-up
tables (median T_ALL over all samples; the phases T_s, the slowest thread's loop and the assembly
after it), the chunk study's best per stencil and schedule kind, and the larger scenes' time and
memory per particle. Every number is measured, except in the table of each --emulation file:
the speed-ups another machine emulated for these thread counts (emulate threads), beside the
ones measured here at the same variant by the earliest sweep (at-<commit>) and by the later
ones (detection-16-*.json), with the emulation's error against each; and in the table of each
--tune file (`tune --threads 16 --predict-only` on another machine): the variant its model
predicted fastest for this many threads, and each structure's best, beside the regret the chunk
study here measured for it within its interleaved rounds (for a chunk it did not measure, the
regrets of the measured chunks just below and above).
"""
import argparse
import glob
import json
import os
import statistics
import sys


def runs_of(path):
    with open(path) as f:
        doc = json.load(f)
    points = {}
    for run in doc["runs"]:
        if run["status"] != "ok":
            continue
        p, s = run["parameters"], run["samples"]
        busy = [max(b) if b else 0.0 for b in s["thread_busy_s"]]
        points[(p["variant"], p["threads"])] = {
            "total": statistics.median(s["total_s"]),
            "setup": statistics.median(s["setup_s"]),
            "loop": statistics.median(busy),
            "assembly": statistics.median([d - b for d, b in zip(s["detect_s"], busy)]),
            "imbalance": statistics.median(s["imbalance"]),
            "samples": len(s["total_s"]),
            "work": run.get("work_counts", {}),
            "scene_n": p["scene"]["n"],
            # T_s's and T_c's parts (samples.parts_s), where the run recorded them.
            "parts": {k: statistics.median(v) for k, v in s.get("parts_s", {}).items()},
        }
    return doc["context"], points


def speedup_table(points, title):
    variants = sorted({v for v, _ in points})
    threads = sorted({t for _, t in points})
    lines = [f"### {title}", "",
             "| variant | " + " | ".join(f"{t} thr T_ALL [s] (x)" for t in threads) +
             " | T_s 1 -> max (x) | assembly 1 -> max [s] |",
             "|---|" + "---|" * (len(threads) + 2)]
    for v in variants:
        one = points.get((v, 1))
        if not one:
            continue
        cells = []
        for t in threads:
            p = points.get((v, t))
            cells.append(f"{p['total']:.4f} ({one['total'] / p['total']:.2f})" if p else "-")
        top = points.get((v, threads[-1]), one)
        cells.append(f"{one['setup']:.4f} -> {top['setup']:.4f} ({one['setup'] / top['setup']:.1f})")
        cells.append(f"{one['assembly']:.4f} -> {top['assembly']:.4f}")
        lines.append(f"| `{v}` | " + " | ".join(cells) + " |")
    return lines


def parts_table(points):
    """Where T_s goes as threads are added: its parts at one thread and at each count, with
    their speed-ups (runs that recorded samples.parts_s only; none for older files)."""
    parts = ("registration", "reorder")
    variants = sorted({v for (v, t), p in points.items()
                       if t == 1 and all(k in p["parts"] for k in parts)})
    if not variants:
        return []
    threads = sorted({t for _, t in points})
    lines = ["T_s's parts (`samples.parts_s`): registration (keys, radix sort, cell index) and "
             "reorder (coordinates into slot order), median seconds (x = speed-up over one "
             "thread); the rest of T_s is single precision's conversion.", "",
             "| variant | part | " + " | ".join(f"{t} thr [s] (x)" for t in threads) + " |",
             "|---|---|" + "---|" * len(threads)]
    for v in variants:
        one = points[(v, 1)]["parts"]
        for part in parts:
            cells = []
            for t in threads:
                p = points.get((v, t))
                at = p["parts"].get(part) if p else None
                cells.append(f"{at:.5f} ({one[part] / at:.2f})" if at else "-")
            lines.append(f"| `{v}` | {part} | " + " | ".join(cells) + " |")
    return lines + [""]


def machine_lines(folder):
    """The folder's machine files (`contactlab probe`): the triad at each thread count and working
    set, and the arithmetic from registers over P x one thread's (whether P threads compute P
    times as fast), for the machine and for two of its cores."""
    lines = []
    for name, title in (("machine-probe.json", "all its cores"),
                        ("machine-probe-2core.json", "two of its cores")):
        path = os.path.join(folder, name)
        if not os.path.exists(path):
            continue
        with open(path) as f:
            doc = json.load(f)
        threads = sorted({p["threads"] for s in doc["working_sets"] for p in s["points"]})
        lines += [f"### The machine, {title}: `{name}` (`contactlab probe`)", "",
                  "| | " + " | ".join(f"{t} thr" for t in threads) + " |",
                  "|---|" + "---|" * len(threads)]
        for s in doc["working_sets"]:
            at = {p["threads"]: p["bytes_per_s"] for p in s["points"]}
            lines.append(f"| triad, {s['bytes'] / 2**20:.0f} MiB [GB/s] | " + " | ".join(
                f"{at[t] / 1e9:.1f}" if t in at else "-" for t in threads) + " |")
        arithmetic = {p["threads"]: p["operations_per_s"] for p in doc.get("arithmetic", [])}
        if arithmetic:
            first = min(arithmetic)
            one = arithmetic[first] / first
            lines.append("| arithmetic, of P x 1 thread | " + " | ".join(
                f"{arithmetic[t] / (t * one):.2f}" if t in arithmetic else "-"
                for t in threads) + " |")
        else:
            lines.append("| arithmetic | (not in this file: probed before it) |")
        lines.append("")
    return lines


def best_over_best(points):
    threads = sorted({t for _, t in points})
    best = {}
    for t in threads:
        at = [(p["total"], v) for (v, tt), p in points.items() if tt == t]
        best[t] = min(at)
    one = best[threads[0]][0]
    return [f"- fastest at {t} thread(s): `{v}` {s:.4f} s, {one / s:.2f}x the fastest at "
            f"{threads[0]}" for t, (s, v) in best.items()]


def chunk_lines(points):
    lines = ["### The chunk study at 16 threads (measured)", "",
             "| loop | block T_ALL [s] | best static,k | best dynamic,k |", "|---|---|---|---|"]
    for stencil in ("full", "half"):
        base = f"particle/sorted/{stencil}/static"
        block = points.get((base, 16))
        row = [f"`particle/sorted/{stencil}`", f"{block['total']:.4f}" if block else "-"]
        for kind in ("static", "dynamic"):
            prefix = f"particle/sorted/{stencil}/{kind},"
            found = [(p["total"], v) for (v, t), p in points.items() if v.startswith(prefix)]
            if found:
                s, v = min(found)
                row.append(f"`{v.split('/')[-1]}` {s:.4f}" +
                           (f" ({block['total'] / s:.2f}x the block)" if block else ""))
            else:
                row.append("-")
        lines.append("| " + " | ".join(row) + " |")
    return lines


def large_lines(folder):
    files = sorted(glob.glob(os.path.join(folder, "large-scenes", "*.json")))
    if not files:
        return []
    rows = {}
    for path in files:
        _, points = runs_of(path)
        for (v, t), p in points.items():
            rows[(p["scene_n"], v, t)] = p
    lines = ["### Larger scenes (the paper's law, D scaled to keep the contacts per particle)", "",
             "| N | variant | threads | T_ALL [s] | T_s [s] | per 10^6 particles [s] | "
             "contact pairs / N | detector bytes / N |", "|---|---|---|---|---|---|---|---|"]
    for (n, v, t), p in sorted(rows.items()):
        kept = p["work"].get("detector_bytes")
        lines.append(f"| {n:,} | `{v}` | {t} | {p['total']:.4f} | {p['setup']:.4f} | "
                     f"{p['total'] / n * 1e6:.4f} | {p['work'].get('contact_pairs', 0) / n:.2f} | "
                     f"{kept / n:.0f} |" if kept else
                     f"| {n:,} | `{v}` | {t} | {p['total']:.4f} | {p['setup']:.4f} | "
                     f"{p['total'] / n * 1e6:.4f} | {p['work'].get('contact_pairs', 0) / n:.2f} | "
                     f"- |")
    return lines


def emulation_lines(path, measured, folder, later=None, later_name=""):
    """The emulated speed-ups beside those measured here by the earliest sweep (`measured`)
    and, where given, by the later sweeps (`later`: the code nearer an emulation of today's)."""
    with open(path) as f:
        doc = json.load(f)
    commit = (doc["context"].get("build", {}).get("git_commit") or "?")[:7]
    later = later or {}
    extra = (f" measured by {later_name} | error against it |" if later else "")
    lines = [f"### Emulated elsewhere against measured here: `{os.path.relpath(path, folder)}` "
             f"(emulated at {commit})", "",
             "| variant | threads | measured speed-up | emulated speed-up | emulation's error |" +
             extra, "|---|---|---|---|---|" + ("---|---|" if later else "")]

    def speedup(points, name, t):
        one, here = points.get((name, 1)), points.get((name, t))
        return one["total"] / here["total"] if one and here else None

    for v in doc["variants"]:
        name = v["variant"]
        for point in v["emulated"]:
            t, emulated = point["threads"], point["speedup"]
            first, second = speedup(measured, name, t), speedup(later, name, t)
            if t == 1 or (first is None and second is None):
                continue
            cells = ([f"{first:.2f}", f"*{emulated:.2f}*†", f"{100 * (emulated / first - 1):+.0f} %"]
                     if first else ["-", f"*{emulated:.2f}*†", "-"])
            if later:
                cells += ([f"{second:.2f}", f"{100 * (emulated / second - 1):+.0f} %"]
                          if second else ["-", "-"])
            lines.append(f"| `{name}` | {t} | " + " | ".join(cells) + " |")
    lines += ["", "† emulated (docs/emulation.md), not measured."]
    if doc.get("bandwidth"):
        lines += [""] + bandwidth_lines(doc, measured)
    return lines


def bandwidth_lines(doc, measured):
    """The loop's bytes (the emulation's count, docs/emulation.md "Bandwidth") over the loop
    measured here: the bandwidth it drew, beside what the emulation's curve gives its threads."""
    b = doc["bandwidth"]
    ceiling = (f"towards {b['ceiling_bytes_per_s'] / 1e9:.0f} GB/s ({b['ceiling_source']})"
               if b["ceiling_bytes_per_s"] > 0 else "the last probed value held")
    lines = [f"Bytes against bandwidth: the emulation's machine file `{b['machine_file']}`, "
             f"beyond its cores {ceiling}. *Drawn here* = the loop's bytes (counted from the work "
             "and the layout) over the slowest thread's loop measured here.", "",
             "| variant | threads | loop bytes [GB] | drawn here [GB/s] | emulated curve [GB/s] |",
             "|---|---|---|---|---|"]
    for v in doc["variants"]:
        name, traffic = v["variant"], v.get("traffic")
        if not traffic:
            continue
        for point in v["emulated"]:
            here = measured.get((name, point["threads"]))
            if not here or not here["loop"] > 0:
                continue
            lines.append(f"| `{name}` | {point['threads']} | {traffic['loop_bytes'] / 1e9:.2f} | "
                         f"{traffic['loop_bytes'] / here['loop'] / 1e9:.1f} | "
                         f"*{point['bytes_per_s'] / 1e9:.1f}*† |")
    return lines


def round_slowdowns(path, threads):
    """Each variant's median over the rounds of (its median T_ALL in the round / the round's
    fastest variant's): ratios within one interleaved run, as the tuner's verification takes
    them, since this VM-class machine moves by 2x between minutes."""
    with open(path) as f:
        doc = json.load(f)
    per_round = {}
    for run in doc["runs"]:
        p, s = run["parameters"], run["samples"]
        if run["status"] != "ok" or p["threads"] != threads:
            continue
        rounds = s.get("round") or [0] * len(s["total_s"])
        by = {}
        for r, t in zip(rounds, s["total_s"]):
            by.setdefault(r, []).append(t)
        per_round[p["variant"]] = {r: statistics.median(v) for r, v in by.items()}
    common = set.intersection(*(set(v) for v in per_round.values())) if per_round else set()
    fastest = {r: min(v[r] for v in per_round.values()) for r in common}
    return {variant: statistics.median(v[r] / fastest[r] for r in common)
            for variant, v in per_round.items()} if common else {}


def tune_lines(path, folder):
    """The model's choice for many threads, predicted on another machine, against the chunk
    study measured here (one interleaved run)."""
    with open(path) as f:
        doc = json.load(f)
    threads = doc["threads"]
    model = next(m for m in doc["methods"] if m["method"] == "model")
    study = os.path.join(folder, "chunk-study-16.json")
    slowdown = round_slowdowns(study, threads) if os.path.exists(study) else {}
    name = os.path.basename(path)
    if not slowdown:
        return [f"### The tuner's prediction `{name}`: no chunk study measured here at "
                f"{threads} threads", ""]
    best = min(slowdown.values())
    best_v = min(slowdown, key=slowdown.get)
    commit = doc["context"]["build"].get("git_commit", "unknown")[:7]
    lines = [f"### The tuner's {threads}-thread choice, predicted elsewhere, against the chunk "
             f"study measured here: `{name}` (predicted at {commit})", "",
             f"The model (calibrated on that machine's cores, no timed run on this scene) priced "
             f"every structure's schedules for {threads} threads. Regret, within the chunk "
             f"study's interleaved rounds: the variant's median slowdown (its T_ALL over the "
             f"round's fastest) over the fastest's (`{best_v}`) - 1. A chunk the study did not "
             f"measure is shown by the study's chunks of the same structure and kind around it.",
             "", "| | variant | predicted T_c [s] | regret measured here |", "|---|---|---|---|"]

    def chunk_of(variant):
        sched = variant.rpartition("/")[2]
        return sched.partition(",")[0], int(sched.partition(",")[2] or 0)

    def row(label, variant, predicted):
        cell = f"| {label} | `{variant}` | *{predicted:.4f}*† | "
        if variant in slowdown:
            return cell + f"{slowdown[variant] / best - 1:+.0%} |"
        head = variant.rpartition("/")[0]
        kind, chunk = chunk_of(variant)
        same = sorted((chunk_of(v)[1], v) for v in slowdown
                      if v.rpartition("/")[0] == head and chunk_of(v)[0] == kind and chunk_of(v)[1])
        below = [v for c, v in same if c < chunk][-1:]
        above = [v for c, v in same if c > chunk][:1]
        near = below + above
        if not chunk or not near:
            return cell + "not measured here |"
        return cell + "not measured; " + ", ".join(
            f"`{v.rpartition('/')[2]}` {slowdown[v] / best - 1:+.0%}" for v in near) + " |"

    lines.append(row("model's choice", model["variant"], model["predicted_s"]))
    for structure in model.get("structures", []):
        lines.append(row("a structure's best", structure["variant"], structure["predicted_s"]))
    lines += ["", "† predicted by the model on another machine (T_c: the loop and the output), "
              "not measured. The regrets are of the code the chunk study ran (its commit in "
              "the README)."]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder")
    parser.add_argument("--out")
    parser.add_argument("--emulation", action="append", default=[])
    parser.add_argument("--tune", action="append", default=[])
    args = parser.parse_args()
    out = args.out or os.path.join(args.folder, "summary.md")
    lines = [f"# Detection on {os.path.basename(os.path.normpath(args.folder))}: measured", "",
             "Generated by `analysis/device_summary.py` from the result files beside it (medians "
             "of every sample; x = speed-up over one thread). Measured, not emulated.", ""]
    found = False
    lines += machine_lines(args.folder)
    for name, title in (("detection-16-sorted.json", "Sorted variants (issue #47's targets)"),
                        ("detection-16-paper.json", "The paper's other loops")):
        path = os.path.join(args.folder, name)
        if os.path.exists(path):
            found = True
            context, points = runs_of(path)
            build = context.get("build", {})
            lines += speedup_table(points, f"{title}: `{name}`") + [""]
            lines += parts_table(points)
            lines += best_over_best(points) + [""]
            lines.append(f"Build: {build.get('flags', '?')} (native: {build.get('native')}); "
                         f"SIMD target: {context.get('simd_target', '?')}.")
            lines.append("")
    olds = sorted(glob.glob(os.path.join(args.folder, "at-*", "paper-tables-16.json")))
    # The later sweeps (the folder's own detection-16-*.json) together, beside the earliest.
    later = {}
    for name in ("detection-16-sorted.json", "detection-16-paper.json"):
        path = os.path.join(args.folder, name)
        if os.path.exists(path):
            later.update(runs_of(path)[1])
    for emulation in args.emulation:
        # Beside the measurement of the code the emulation ran: the earliest sweep here, and
        # the later sweeps for an emulation of later code.
        _, points = runs_of(olds[0]) if olds else ({}, {})
        lines += emulation_lines(emulation, points, args.folder, later,
                                 "`detection-16-*.json`") + [""]
    for old in olds:
        _, points = runs_of(old)
        lines += speedup_table(points, f"The same at {old.split(os.sep)[-2][3:]}: "
                                       f"`{os.path.relpath(old, args.folder)}`") + [""]
    chunk = os.path.join(args.folder, "chunk-study-16.json")
    if os.path.exists(chunk):
        found = True
        lines += chunk_lines(runs_of(chunk)[1]) + [""]
    for tune in args.tune:
        lines += tune_lines(tune, args.folder) + [""]
    large = large_lines(args.folder)
    lines += large + ([""] if large else [])
    if not found and not large:
        sys.exit(f"device_summary: {args.folder}: no result file of scripts/device-16core")
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines))
    os.replace(tmp, out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()

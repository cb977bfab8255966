#!/usr/bin/env python3
"""Tables and figures of the study, from results/ only (and the paper's own numbers).

usage: /usr/bin/python3 analysis/make_tables.py RESULTS_DIR PAPER_JSON

Writes RESULTS_DIR/tables.md and RESULTS_DIR/figures/*.png. Every number of ours comes from a
result file written by contactlab (machine and commit in its context); the paper's numbers are
labelled as such; nothing is extrapolated.
"""
import json
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt


class SchemaError(Exception):
    pass


def need(obj, path, *keys):
    """obj[keys[0]][keys[1]]..., or SchemaError naming the JSON path."""
    for key in keys:
        if isinstance(key, int):
            if not isinstance(obj, list) or key >= len(obj):
                raise SchemaError(f"{path}[{key}]: missing")
            path = f"{path}[{key}]"
        else:
            if not isinstance(obj, dict) or key not in obj:
                raise SchemaError(f"{path}.{key}: missing")
            path = f"{path}.{key}"
        obj = obj[key]
    return obj


def load_results(path):
    """A result file (docs/result-schema.md): checked for the fields this script reads."""
    with open(path) as f:
        document = json.load(f)
    if need(document, "$", "schema_version") != 1:
        raise SchemaError(f"{path}: $.schema_version: expected 1")
    for i, run in enumerate(need(document, "$", "runs")):
        for key in ("status", "parameters", "aggregates", "work", "counters"):
            need(run, f"$.runs[{i}]", key)
    return document


def context_line(document):
    ctx = need(document, "$", "context")
    machine, build = need(ctx, "$.context", "machine"), need(ctx, "$.context", "build")
    return (f"{machine.get('cpu_model', '?')}, {machine.get('cores', '?')} cores; "
            f"commit {build.get('git_commit', '?')[:10]}{' (dirty)' if build.get('git_dirty') else ''}; "
            f"{ctx.get('date_utc', '?')}")


def ok_runs(document):
    return [r for r in document["runs"] if r["status"] == "ok"]


def median_of(run, field):
    return need(run, "$.run", "aggregates", field, "median")


def paper_tables(results_dir, paper, out):
    path = os.path.join(results_dir, "paper-tables.json")
    if not os.path.exists(path):
        out.append("_results/paper-tables.json not found: run scripts/study._\n")
        return None
    document = load_results(path)
    out.append(f"## Tables 2–5 and 7: T_ALL = T_s + T_c (seconds), N = 1,024,000, D = 1/200\n")
    out.append(f"Ours: {context_line(document)}. Median of the timed repetitions. "
               "The paper: FX10, 16 cores per node (their scene's density law is not given; ours is "
               "docs/scenes.md). Threads beyond this machine's cores are not measured here.\n")
    runs = {(r["parameters"]["variant"], r["parameters"]["threads"]): r for r in ok_runs(document)}
    curves = {}
    for number, table in sorted(paper["tables"].items()):
        variant = table["variant"]
        out.append(f"\n**Table {number}** — `{variant}`\n")
        out.append("| threads | paper T_ALL | paper speedup | ours T_s | ours T_c | ours T_ALL | ours speedup |")
        out.append("|---|---|---|---|---|---|---|")
        serial = runs.get((variant, 1))
        ours_curve = []
        for t, t_all, speedup in zip(table["threads"], table["t_all"], table["speedup"]):
            run = runs.get((variant, t))
            if run:
                total = median_of(run, "total_s")
                s = median_of(serial, "total_s") / total if serial else None
                ours = (f"{median_of(run, 'setup_s'):.4f} | {median_of(run, 'detect_s'):.4f} | {total:.4f} | "
                        + (f"{s:.2f}" if s else "–"))
                if s:
                    ours_curve.append((t, s))
            else:
                ours = "– | – | – | –"
            out.append(f"| {t} | {t_all} | {speedup if speedup else '–'} | {ours} |")
        curves[number] = (table, ours_curve)
    # Speed claims of the foundation issue, as ratios within this one run.
    def total(v, t=1):
        r = runs.get((v, t))
        return median_of(r, "total_s") if r else None
    unsorted, sorted_ = total("particle/unsorted/full/static"), total("particle/sorted/full/static")
    if unsorted and sorted_:
        out.append(f"\nReordering at 1 thread: particle/unsorted / particle/sorted T_ALL = "
                   f"**{unsorted / sorted_:.1f}x** (paper 8.273 / 2.005 = 4.1x).\n")
    return curves


def figure8(curves, figures_dir):
    if not curves:
        return None
    fig, ax = plt.subplots(figsize=(6, 4))
    for number, style in (("4", "o"), ("7", "s")):
        table, ours = curves[number]
        threads = table["threads"][1:]
        ax.plot(threads, table["speedup"][1:], style + "--", label=f"paper Table {number}: {table['variant']} (FX10)")
        if ours:
            ax.plot([t for t, _ in ours], [s for _, s in ours], style + "-", label=f"ours, measured: {table['variant']}")
    ax.plot([1, 16], [1, 16], ":", color="grey", label="ideal")
    ax.set_xlabel("threads")
    ax.set_ylabel("speedup over 1 thread (T_ALL)")
    ax.set_title("Fig. 8: block vs block-cyclic (chunk 200), reordered")
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(figures_dir, "fig8_speedup.png")
    fig.savefig(path, dpi=110)
    return path


def table6(results_dir, paper, out):
    path = os.path.join(results_dir, "table6-cache.json")
    if not os.path.exists(path):
        return
    document = load_results(path)
    out.append("\n## Table 6: data-cache miss rates (%)\n")
    out.append(f"Ours: {context_line(document)}. PAPI where the CPU exposes counters; otherwise "
               "callgrind's simulation of an FX10-like cache (**simulated, an approximation**: "
               "32 KiB 2-way L1D, 12 MiB L2, 128-byte lines), detection loop only.\n")
    out.append("| variant | paper L1 | paper L2 | ours L1 | ours L2 | source |")
    out.append("|---|---|---|---|---|---|")
    runs = {r["parameters"]["variant"]: r for r in ok_runs(document)}
    for row in paper["table6_miss_rates_percent"]:
        run = runs.get(row["variant"])
        cells = "– | – | –"
        if run:
            counted = [c for c in run["counters"] if c["available"]]
            if counted:
                c = counted[0]
                cells = f"{c['l1_miss_percent']:.3f} | {c['l2_miss_percent']:.3f} | {c['source']}"
            else:
                cells = "– | – | " + "; ".join(f"{c['source']}: unavailable" for c in run["counters"])
        out.append(f"| `{row['variant']}` | {row['l1']} | {row['l2']} | {cells} |")


def chunk_study(results_dir, out, figures_dir):
    path = os.path.join(results_dir, "chunk-study.json")
    if not os.path.exists(path):
        return
    document = load_results(path)
    out.append("\n## Time against chunk size (2 threads, particle/sorted/full, N = 1,024,000)\n")
    out.append(f"Ours: {context_line(document)}.\n")
    series = {}
    block = None
    for run in ok_runs(document):
        variant = run["parameters"]["variant"]
        schedule = variant.split("/")[-1]
        if "," not in schedule:
            block = median_of(run, "detect_s")
            continue
        kind, k = schedule.split(",")
        series.setdefault(kind, []).append((int(k), median_of(run, "detect_s")))
    fig, ax = plt.subplots(figsize=(6, 4))
    for kind, points in sorted(series.items()):
        points.sort()
        ax.semilogx([k for k, _ in points], [t for _, t in points], "o-", base=2, label=f"{kind},k (measured)")
        best = min(points, key=lambda p: p[1])
        out.append(f"- `{kind},k`: fastest k = {best[0]} at T_c {best[1]:.4f} s; "
                   f"k = 1: {points[0][1]:.4f} s; k = {points[-1][0]}: {points[-1][1]:.4f} s")
    if block:
        ax.axhline(block, linestyle="--", color="grey", label="static (block), measured")
        out.append(f"- `static` (block): T_c {block:.4f} s")
    ax.set_xlabel("chunk size k")
    ax.set_ylabel("T_c [s] (median)")
    ax.set_title("chunk size study, 2 threads")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(figures_dir, "chunk_study.png"), dpi=110)


def tuning(results_dir, out):
    tuning_dir = os.path.join(results_dir, "tuning")
    if not os.path.isdir(tuning_dir):
        return
    out.append("\n## Tuning: model vs search vs exhaustive (2 threads)\n")
    out.append("T_c median and regret come from a final verification in which every distinct "
               "choice (the methods' and the classic formulas') is timed once per round, in a new "
               "random order each round. Regret = median of the per-round ratios to the fastest "
               "verified choice − 1; \"vs exhaustive\" = the same against the exhaustive best "
               "(the issue's target); brackets: 95% intervals of those medians. Cost = seconds the "
               "method spent choosing (the search's includes the screening and the model it is "
               "seeded by); timed runs = runs on the scene.\n")
    out.append("| scene | method | choice | T_c median [s] | regret [95% CI] | vs exhaustive [95% CI] | cost [s] | timed runs |")
    out.append("|---|---|---|---|---|---|---|---|")
    predictions = []
    for name in sorted(os.listdir(tuning_dir)):
        if not name.endswith(".json"):
            continue
        with open(os.path.join(tuning_dir, name)) as f:
            t = json.load(f)
        if need(t, "$", "schema_version") != 1:
            raise SchemaError(f"{name}: $.schema_version: expected 1")
        scene = name[:-5]
        rounds = t.get("verification", {}).get("rounds", "?")

        def relative(entry, key, interval_key):
            if key not in entry:
                return "–"
            value = entry[key] if interval_key else entry[key]["ratio_minus_one"]
            ci = entry[interval_key] if interval_key else entry[key]["ci95"]
            return f"{100 * value:+.1f}% [{100 * ci[0]:+.1f}, {100 * ci[1]:+.1f}]"

        exhaustive = next((m for m in t["methods"] if m["method"] == "exhaustive"), None)
        for m in need(t, "$", "methods"):
            measured = m.get("measured", {})
            median = f"{measured['median_s']:.4f}" if measured else "–"
            out.append(f"| {scene} | {m['method']} | `{m['variant']}` | {median} | "
                       f"{relative(m, 'regret', 'regret_ci95')} | {relative(m, 'vs_exhaustive', None)} | "
                       f"{m['tuning_cost_s']:.1f} | {m.get('timed_runs', '–')} |")
        for c in need(t, "$", "classic"):
            out.append(f"| {scene} | classic: {c['name']} ({c['inputs']}) | `{c.get('variant', c['chunk'])}` | "
                       f"{c.get('measured', {}).get('median_s', float('nan')):.4f} | "
                       f"{relative(c, 'regret', 'regret_ci95')} | {relative(c, 'vs_exhaustive', None)} | – | – |")
        search = next((m for m in t["methods"] if m["method"] == "search"), None)
        if search and exhaustive:
            out.append(f"| {scene} | search / exhaustive cost | | | | | "
                       f"{search['chunk_search_cost_s'] / exhaustive['tuning_cost_s']:.0%} (chunk search), "
                       f"{search['tuning_cost_s'] / exhaustive['tuning_cost_s']:.0%} (all of it) | "
                       f"{search.get('chunk_search_timed_runs', '–')} / {exhaustive['timed_runs']} |")
        out.append(f"| {scene} | verification | | | {rounds} rounds | | | |")
        for p in t.get("predictions", []):
            predictions.append((scene, p))
    if predictions:
        out.append("\n**Model predictions for other thread counts** (predicted, not measured: this "
                   "machine has 2 cores):\n")
        out.append("| scene | threads | predicted choice | predicted T_c [s] |")
        out.append("|---|---|---|---|")
        for scene, p in predictions:
            out.append(f"| {scene} | {p['threads']} | `{p['variant']}` | {p['predicted_s']:.4f} |")


def benchmark(results_dir, out):
    path = os.path.join(results_dir, "benchmark.json")
    if not os.path.exists(path):
        return
    with open(path) as f:
        b = json.load(f)
    ctx = b.get("context", {})
    out.append("\n## Kernel benchmark (Google Benchmark, N = 1,024,000, D = 1/200, clustered)\n")
    out.append(f"{ctx.get('host_name', '?')}, {ctx.get('num_cpus', '?')} CPUs, {ctx.get('date', '?')}. "
               "Time = T_ALL per iteration (manual time, mean of the iterations).\n")
    out.append("| benchmark | T_ALL [ms] | T_s [ms] | T_c [ms] | tests/s | contacts/s |")
    out.append("|---|---|---|---|---|---|")
    rows = {}
    for bm in b.get("benchmarks", []):
        if bm.get("run_type") == "aggregate":
            continue
        name = bm["name"].replace("detect/", "").replace("/manual_time", "")
        rows[name] = bm
        out.append(f"| `{name}` | {bm['real_time']:.1f} | {1e3 * bm['T_s']:.1f} | {1e3 * bm['T_c']:.1f} | "
                   f"{bm['tests_per_s']:.3g} | {bm['contacts_per_s']:.3g} |")

    def t(name):
        bm = rows.get(name)
        return bm["real_time"] if bm else None

    claims = []
    u, s = t("particle/unsorted/full/static/threads:1"), t("particle/sorted/full/static/threads:1")
    if u and s:
        claims.append(f"reordering: particle/unsorted / particle/sorted T_ALL = **{u / s:.2f}x** (target >= 3x)")
    f_, h = t("particle/sorted/full/static/threads:1"), t("particle/sorted/half/static/threads:1")
    if f_ and h:
        claims.append(f"half stencil: full / half T_ALL (sorted, static) = **{f_ / h:.2f}x** (target >= 1.4x)")
    ts = rows.get("particle/sorted/full/static/threads:1")
    if ts:
        claims.append(f"T_s of 1,024,000 particles, sorted, 1 thread = **{1e3 * ts['T_s']:.1f} ms** (target < 60 ms)")
    if claims:
        out.append("\nSpeed targets (ratios within this one benchmark run, 1 thread):\n")
        out.extend(f"- {c}" for c in claims)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    results_dir, paper_path = sys.argv[1], sys.argv[2]
    figures_dir = os.path.join(results_dir, "figures")
    os.makedirs(figures_dir, exist_ok=True)
    try:
        with open(paper_path) as f:
            paper = json.load(f)
        out = ["# Results\n",
               "Generated by `analysis/make_tables.py` from the result files in this folder "
               "(`scripts/study`); do not edit by hand.\n"]
        curves = paper_tables(results_dir, paper, out)
        if figure8(curves, figures_dir):
            out.append("\n![Fig. 8](figures/fig8_speedup.png)\n")
        table6(results_dir, paper, out)
        chunk_study(results_dir, out, figures_dir)
        if os.path.exists(os.path.join(figures_dir, "chunk_study.png")):
            out.append("\n![chunk study](figures/chunk_study.png)\n")
        tuning(results_dir, out)
        benchmark(results_dir, out)
    except (OSError, ValueError, SchemaError, KeyError) as error:
        sys.exit(f"make_tables: {error}")
    temporary = os.path.join(results_dir, "tables.md.tmp")
    with open(temporary, "w") as f:
        f.write("\n".join(out) + "\n")
    os.replace(temporary, os.path.join(results_dir, "tables.md"))
    print(f"wrote {os.path.join(results_dir, 'tables.md')}")


if __name__ == "__main__":
    main()

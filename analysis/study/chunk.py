"""The paper's open problem, the block-cyclic chunk size: T_c against k at 2 threads with 95 %
intervals, the emulated best chunk at more threads against the tuner's predictions, and the
headline answer. A difference is claimed only where the sweep shows one: with a sweep in rounds,
where the median of the per-round ratios has a 95 % interval clear of 1 (a slow spell of the
machine slows both sides of a round's ratio); without rounds, where the two medians' intervals
do not overlap."""
from types import SimpleNamespace

from . import tuning
from .common import (cell, context_line, emulated, load_results, num, ok_runs, plt, predicted,
                     reading, round_medians, run_ratio, save_figure, summary, table)


def collect(path):
    """{schedule: [(k, Interval)]}, the block schedule's Interval, threads, scene; None if absent."""
    if path is None:
        return None
    document = load_results(path)
    series, block, threads, scene, by_variant, rounds = {}, None, set(), None, {}, {}
    with reading(path):
        for run_path, run in ok_runs(document):
            variant = run["parameters"]["variant"]
            value = summary(run, run_path, "detect_s")
            by_variant[variant] = value
            rounds[variant] = round_medians(run, run_path, "detect_s")
            threads.add(run["parameters"]["threads"])
            scene = scene or run["parameters"].get("scene")
            schedule = variant.split("/")[-1]
            if "," not in schedule:
                block = value
                continue
            kind, k = schedule.split(",")
            series.setdefault(kind, []).append((int(k), value))
    for points in series.values():
        points.sort()
    paired = bool(rounds) and all(r is not None for r in rounds.values())
    round_count = len(set().union(*(r.keys() for r in rounds.values()))) if paired else 0
    return SimpleNamespace(series=series, block=block, threads=sorted(threads), scene=scene or {},
                           by_variant=by_variant, rounds=rounds if paired else {},
                           round_count=round_count, context=context_line(document))


def _variant_of(study, value):
    """The variant whose summary is `value` (series and block hold the summaries themselves)."""
    return next(v for v, x in study.by_variant.items() if x is value)


def _compare(study, value, reference):
    """value's T_c over reference's: (ratio Interval, whether it is a real difference, how it
    was measured)."""
    if study.rounds:
        r = run_ratio(value, reference, study.rounds[_variant_of(study, value)],
                      study.rounds[_variant_of(study, reference)])
        return r, r.low > 1.0 or r.high < 1.0, f"median of {study.round_count} rounds' ratios"
    r = run_ratio(value, reference)
    return r, not value.overlaps(reference), "independent medians"


def _percent(r):
    return f"{100 * (r.median - 1):+.1f}% [{100 * (r.low - 1):+.1f}, {100 * (r.high - 1):+.1f}]"


def _best(points):
    return min(points, key=lambda p: p[1].median)


def section(study, emulation, tunings, figures_dir, out):
    out.append("\n## The open problem: time against chunk size k\n")
    if study is None:
        out.append("Not run (no chunk-study.json).")
    else:
        threads = ", ".join(str(t) for t in study.threads)
        rule = (f"the sweep ran in {study.round_count} rounds (every point once a round, in a "
                "new order each): **a difference is claimed only when the median of the rounds' "
                "ratios has a 95 % interval clear of 1.**" if study.rounds else
                "**A difference between two k is claimed only when their intervals do not "
                "overlap.**")
        out.append(f"Ours: {study.context}; {threads} threads, `particle/sorted/full`, scene "
                   f"{study.scene.get('kind', '?')} N = {study.scene.get('n', '?')}. T_c median "
                   f"[95 % interval]; {rule}\n")
        out.extend(_real_differences(study))
        out.append(f"\n![chunk study]({_figure(study, figures_dir)})")
    tuning.section(tunings, out)
    _emulated_vs_predicted(emulation, tunings, out)


def _real_differences(study):
    lines = []
    bests = {}
    for kind, points in sorted(study.series.items()):
        k_best, best = _best(points)
        bests[kind] = (k_best, best)
        real = {k: _compare(study, v, best)[1] for k, v in points if v is not best}
        slower = [k for k, _ in points if real.get(k)]
        tied = [k for k, _ in points if not real.get(k)]
        same, differ = (("ratio's interval holds 1", "ratio's interval above 1") if study.rounds
                        else ("intervals overlap", "no overlap"))
        lines.append(f"- `{kind},k`: fastest median at k = {k_best}, T_c {cell(best)} s. "
                     f"Indistinguishable from it ({same}): k = {', '.join(map(str, tied))}. "
                     + (f"Really slower ({differ}): k = {', '.join(map(str, slower))}."
                        if slower else "No k is really slower: the sweep cannot tell the chunk sizes apart."))
    if study.block:
        lines.append(f"- `static` (block): T_c {cell(study.block)} s.")
    candidates = list(bests.items()) + ([("static (block)", (None, study.block))] if study.block else [])
    if len(candidates) >= 2:
        name, (k, fastest) = min(candidates, key=lambda c: c[1][1].median)
        label = f"`{name},{k}`" if k else f"`{name}`"
        for other, (k2, v) in candidates:
            if v is fastest:
                continue
            other_label = f"`{other},{k2}`" if k2 else f"`{other}`"
            r, real, how = _compare(study, v, fastest)
            if study.rounds:
                verdict = (f"{other_label} {_percent(r)} ({how}): "
                           + ("a real difference" if real else "not a real difference"))
            else:
                verdict = ("a real difference (intervals do not overlap)" if real
                           else "not a real difference (intervals overlap)")
            lines.append(f"- {label} against the best of {other_label}: "
                         f"{num(fastest.median)} vs {num(v.median)} s, {verdict}.")
    return lines


def _figure(study, figures_dir):
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for (kind, points), marker in zip(sorted(study.series.items()), "os^"):
        ks = [k for k, _ in points]
        ax.errorbar(ks, [v.median for _, v in points],
                    yerr=[[v.median - v.low for _, v in points], [v.high - v.median for _, v in points]],
                    fmt=marker + "-", capsize=3, label=f"{kind},k measured (median, 95 % interval)")
    if study.block:
        ax.axhline(study.block.median, linestyle="--", color="grey", label="static (block) measured, median")
        ax.axhspan(study.block.low, study.block.high, color="grey", alpha=0.15,
                   label="static (block) 95 % interval")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("chunk size k")
    ax.set_ylabel("T_c [s]")
    ax.set_title(f"chunk size study, {', '.join(map(str, study.threads))} threads (measured)")
    ax.legend(fontsize=7)
    return save_figure(fig, figures_dir, "chunk_study.png")


def _emulated_vs_predicted(emulation, tunings, out):
    out.append("\n**Best chunk at more threads: emulated against the tuner model's prediction**\n")
    predictions = tuning.predictions(tunings)
    if emulation is None or not emulation.chunk_study:
        out.append("Emulated chunk study not run (no emulation-threads.json or an empty chunk_study).")
        tuning.predictions_table(tunings, out)
        return
    rows = []
    for c in sorted(emulation.chunk_study, key=lambda c: (c.threads, c.schedule)):
        if c.threads not in (4, 8, 16):
            continue
        guesses = "; ".join(f"{scene}: `{variant}` {predicted(f'{s:.4f}')} s"
                            for scene, threads, variant, s in predictions if threads == c.threads) or "–"
        # The classic formulas beside the emulated best: their chunk and its excess time.
        classic = "; ".join(f"{k.name} k = {k.chunk}: {emulated(f'{k.detect_s / c.best_detect_s - 1:+.1%}')}"
                            for k in c.classic) or "–"
        rows.append([c.threads, c.schedule, emulated(str(c.best_chunk)), emulated(num(c.best_detect_s)),
                     emulated(num(c.block_detect_s)), classic, guesses])
    out.append(f"Emulated on {emulation.scene.get('kind', '?')} N = {emulation.scene.get('n', '?')} "
               "(`particle/sorted/full`); the tuner chooses among structures too, so its choice "
               "may not be `full`.\n")
    out.extend(table(["threads", "schedule", "emulated best k", "emulated best T_c [s]",
                      "emulated block T_c [s]", "classic formulas (dynamic,k) over the best",
                      "tuner model's prediction (scene: choice, T_c)"], rows)
               if rows else ["(no emulated chunk study at 4, 8 or 16 threads)"])
    tuning.predictions_table(tunings, out)


def headline(study, tunings):
    """The open problem's answer at 2 threads: the tuner's choice against the swept best."""
    if study is None:
        return ["- Open problem (chunk size): not run (no chunk-study.json)."]
    everything = [(f"{kind},{k}", v) for kind, points in study.series.items() for k, v in points]
    if study.block:
        everything.append(("static", study.block))
    if not everything:
        return ["- Open problem (chunk size): chunk-study.json holds no ok runs."]
    name, best = min(everything, key=lambda e: e[1].median)
    lines = [f"- Open problem (chunk size), swept at {', '.join(map(str, study.threads))} threads: the "
             f"fastest median is `{name}` at T_c {cell(best)} s."]
    chosen = tuning.paper_scene(tunings, study.scene)
    if chosen is None:
        lines.append("- The tuner: not run on this scene (no tuning file with its kind and N).")
        return lines
    scene, t = chosen
    for m in t["methods"]:
        if m["method"] == "exhaustive":
            continue
        text = f"- Tuner ({m['method']}, tuning/{scene}.json) chose `{m['variant']}`"
        regret = m.get("vs_exhaustive")
        if regret:
            low, high = regret["ci95"]
            text += (f": regret against the exhaustive best {100 * regret['ratio_minus_one']:+.1f}% "
                     f"[95 %: {100 * low:+.1f}, {100 * high:+.1f}]")
        swept = study.by_variant.get(m["variant"])
        if swept:
            r, _, how = _compare(study, swept, best)
            text += (f"; in the sweep its T_c is {cell(swept)} s, {_percent(r)} against the swept "
                     f"best ({how})")
        else:
            text += "; its choice is not among the swept variants (the sweep is `particle/sorted/full` only)"
        lines.append(text + ".")
    return lines

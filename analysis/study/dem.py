"""Otsuka (2011): the DEM profile (phase split, serial fraction, Amdahl bounds, speed-up
measured and emulated) beside the report's numbers, and the ant-lion pit and Beverloo
discharge of our own DEM runs, linked where they exist."""
import os
import re

from .common import (cell, context_line, emulated, load_json, need, number, percent,
                     plt, ratio_interval, reading, relative_error, save_figure, speedup_cell, table)


def amdahl(serial_fraction, threads):
    return 1.0 / (serial_fraction + (1.0 - serial_fraction) / threads)


def section(profile, otsuka, results_dir, figures_dir, out):
    out.append("\n## Otsuka (2011): where a DEM step's time goes, and how far threads take it\n")
    out.append(f"The report: {otsuka['source']}\n")
    if profile is None:
        out.append("Profile not run (no dem-profile.json).")
    else:
        _profile(profile, otsuka, figures_dir, out)
    _pit(results_dir, otsuka, out)
    _beverloo(results_dir, out)


def _profile(p, otsuka, figures_dir, out):
    out.append(f"Ours: {context_line(p.document)}; config `{p.config}`, {p.particles} particles, "
               f"force variant `{p.variant}`, {p.steps} steps × {p.rounds} rounds. Method: {p.method}\n")
    split = p.split
    total = sum(split.values())
    # Otsuka's three categories: the force pass (pairs, their reduction, walls and the
    # per-contact update) is "contact force"; integration is "coordinate/velocity update".
    force = split["pair_forces_s"] + split["reduction_s"] + split["wall_forces_s"] + split["update_s"]
    ours = {"contact_force": force, "coordinate_velocity_update": split["integration_s"],
            "candidate_detection": split["candidates_s"]}
    theirs = otsuka["profile"]["percent"]
    rows = [[name.replace("_", " "), f"{theirs[name]}%", f"{100 * ours[name] / total:.1f}%",
             f"{1e3 * ours[name]:.4g}"] for name in theirs]
    out.append(f"**Phase split at 1 thread** (Otsuka: {otsuka['profile']['particles']} particles; "
               "ours: contact force = pair forces + reduction + wall forces + contact update, "
               "coordinate/velocity update = integration):\n")
    out.extend(table(["phase", "Otsuka", "ours", "ours [ms/step]"], rows))
    bound8 = otsuka["amdahl_at_8_threads"]
    force_only = 1 - theirs["contact_force"] / 100
    force_update = 1 - (theirs["contact_force"] + theirs["coordinate_velocity_update"]) / 100
    out.append(f"\nSerial fraction (ours, from the file): **{p.serial_fraction:.3f}**. Otsuka's "
               f"split gives {force_only:.2f} with only the force parallel and {force_update:.2f} "
               "with force and update parallel.\n")
    rows = []
    for threads in (2, 8, 16):
        ours_bound = p.bounds.get(threads)
        paper = (f"{bound8['force_only_parallel']}x (force only), {bound8['force_and_update_parallel']}x "
                 "(force + update)" if threads == bound8["threads"] else
                 f"{amdahl(force_only, threads):.2f}x / {amdahl(force_update, threads):.2f}x (from the split)")
        rows.append([threads, paper, f"{ours_bound:.2f}x" if ours_bound else "–",
                     f"{amdahl(p.serial_fraction, threads):.2f}x"])
    out.extend(table(["threads", "Otsuka's Amdahl bound", "ours (file)", "ours 1/(f + (1−f)/P)"], rows))
    _speedup(p, otsuka, figures_dir, out)


def _speedup(p, otsuka, figures_dir, out):
    base = p.measured[1].step
    rows = []
    for threads in sorted(set(p.measured) | set(p.emulated)):
        bound = p.bounds.get(threads)
        if threads in p.measured:
            m = p.measured[threads]
            s = ratio_interval(base, m.step)
            check = "–"
            if threads in p.emulated:
                e = p.emulated[threads].step_s
                check = f"{emulated(f'{e:.4g}')} ({percent(relative_error(e, m.step.median))})"
            rows.append([threads, cell(m.step), "1" if threads == 1 else speedup_cell(s), check,
                         f"{bound:.2f}x" if bound else "–"])
        else:
            e = p.emulated[threads]
            rows.append([threads, emulated(f"{e.step_s:.4g}"), emulated(f"{e.speedup:.2f}"), "–",
                         f"{bound:.2f}x" if bound else "–"])
    out.append("\n**Speed-up** (measured: median [95 % interval], speed-up interval "
               "[T1.low / TP.high, T1.high / TP.low]; beyond the measured threads emulated):\n")
    out.extend(table(["threads", "step [s]", "speed-up", "emulated step (error)", "Amdahl bound"], rows))
    hopper = otsuka["hopper"]
    e8 = p.emulated.get(hopper["threads"])
    text = (f"\nOtsuka's hopper ({hopper['particles']:,} particles): best {hopper['best_speedup']}x on "
            f"{hopper['threads']} threads ({hopper['compiler']}), against an Amdahl bound of "
            f"{hopper['amdahl_bound']}x ({hopper['best_speedup'] / hopper['amdahl_bound']:.0%} of it).")
    if e8 and p.bounds.get(hopper["threads"]):
        b = p.bounds[hopper["threads"]]
        text += (f" Ours at {hopper['threads']} threads: {emulated(f'{e8.speedup:.2f}x')} against our "
                 f"bound {b:.2f}x ({e8.speedup / b:.0%} of it).")
    out.append(text)
    for r in p.validation:
        out.append(f"\nEmulation checked at {r.threads} threads: measured {r.measured:.4g} s, emulated "
                   f"{r.estimate:.4g} s, error {percent(relative_error(r.estimate, r.measured))}.")
    out.append(f"\n![DEM speed-up]({_figure(p, figures_dir)})")


def _figure(p, figures_dir):
    base = p.measured[1].step
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    measured = sorted(p.measured.items())
    speedups = [ratio_interval(base, m.step) for _, m in measured]
    ax.errorbar([t for t, _ in measured], [s.median for s in speedups],
                yerr=[[s.median - s.low for s in speedups], [s.high - s.median for s in speedups]],
                fmt="o-", capsize=3, label="ours measured (95 % interval)")
    if p.emulated:
        points = sorted(p.emulated.items())
        ax.plot([t for t, _ in points], [e.speedup for _, e in points], "s:", mfc="none",
                label="ours emulated")
    if p.bounds:
        points = sorted(p.bounds.items())
        ax.plot([t for t, _ in points], [b for _, b in points], "--", color="tab:red",
                label=f"Amdahl bound, serial fraction {p.serial_fraction:.3f}")
    top = int(max(list(p.emulated) + list(p.measured)))
    ax.plot([1, top], [1, top], "-", color="grey", lw=0.8, label="ideal")
    ax.set_xscale("log", base=2)  # log-log, as Fig. 8: the ideal line is straight
    ax.set_yscale("log", base=2)
    ticks = [2 ** k for k in range(top.bit_length()) if 2 ** k <= top]
    ax.set_xticks(ticks, [str(t) for t in ticks])
    ax.set_yticks(ticks, [str(t) for t in ticks])
    ax.set_xlabel("threads")
    ax.set_ylabel("speed-up over 1 thread (step time)")
    ax.set_title(f"DEM step speed-up, {p.config} ({p.particles} particles)")
    ax.legend(fontsize=7)
    return save_figure(fig, figures_dir, "dem_speedup.png")


def _pit(results_dir, otsuka, out):
    """The hopper's pictures (../dem/pit/hopper-small), in time order when pictures.json says."""
    relative = os.path.join("..", "dem", "pit", "hopper-small")
    folder = os.path.join(results_dir, relative)
    small = otsuka["small_hopper"]
    out.append(f"\n**The ant-lion pit.** Otsuka: in a small hopper of {small['particles']:,} particles "
               f"{small['observation']}.\n")
    pngs = sorted(n for n in os.listdir(folder) if n.endswith(".png")) if os.path.isdir(folder) else []
    if not pngs:
        out.append(f"Pictures not run (no {relative}/*.png).")
        return
    captions = {}
    pictures_json = os.path.join(folder, "pictures.json")
    if os.path.exists(pictures_json):
        with reading(pictures_json):
            captions = need(load_json(pictures_json), "$", "pictures")
    def time_of(name):
        match = re.match(r"\s*t\s*=\s*([0-9.]+)\s*s", str(captions.get(name, "")))
        return float(match.group(1)) if match else float("inf")
    for name in sorted(pngs, key=lambda n: (time_of(n), n)):
        link = os.path.join(relative, name).replace(os.sep, "/")
        out.append(f"- [{name}]({link}): {captions.get(name, '(no caption)')}")


def _beverloo(results_dir, out):
    relative = os.path.join("..", "dem", "beverloo", "beverloo.json")
    path = os.path.join(results_dir, relative)
    out.append("\n**Discharge rate against orifice (Beverloo).**")
    if not os.path.exists(path):
        out.append(f"Not run (no {relative}).")
        return
    b = load_json(path)
    with reading(path):
        fit = need(b, "$", "fit")
        c, k, r2 = number(fit, "$.fit", "C"), number(fit, "$.fit", "k"), number(fit, "$.fit", "r_squared")
        targets = b.get("targets", {})
        seeds = b.get("setup", {}).get("seeds", [])
        interval = (f" (95 % interval over {len(seeds)} fills: C {_span(fit['C_interval'], 3)}, "
                    f"k {_span(fit['k_interval'], 2)})" if fit.get("C_interval") else "")
        out.append(f"Fit of W = C ρ_b √g (D − k d)^2.5 over the steady orifices "
                   f"([{relative}]({relative.replace(os.sep, '/')})): C = {c:.3f}, k = {k:.2f}"
                   f"{interval}, R² = {r2:.4f}"
                   + (f"; literature ranges C {targets['C']}, k {targets['k']}: "
                      f"{'inside' if b.get('in_target') else 'outside'}" if 'C' in targets and 'k' in targets else "")
                   + ".\n")
        rows = []
        for i, o in enumerate(need(b, "$", "orifices")):
            where = f"$.orifices[{i}]"
            rate = number(o, where, "rate_kg_s")
            spread = o.get("rate_interval_kg_s")
            rows.append([number(o, where, "orifice_over_d"), f"{rate:.4g}",
                         _span(spread, 4, "g") if spread else "-",
                         len(o.get("seed_rates_kg_s", [rate])),
                         "yes" if o.get("steady") else "no", "yes" if o.get("in_fit") else "no"])
    out.extend(table(["D / d", "rate [kg/s]", "95 % interval", "fills", "steady (every fill)", "in fit"], rows))
    png = os.path.join(os.path.dirname(path), "beverloo.png")
    if os.path.exists(png):
        out.append(f"\n![Beverloo]({os.path.join(os.path.dirname(relative), 'beverloo.png').replace(os.sep, '/')})")


def _span(bounds, digits, kind="f"):
    return f"{bounds[0]:.{digits}{kind}} – {bounds[1]:.{digits}{kind}}"


def validation_rows(profile):
    if profile is None:
        return []
    return [("DEM", f"{profile.config}, {r.threads} threads, step", r) for r in profile.validation]


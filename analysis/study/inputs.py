"""Readers of the files `contactlab emulate threads`, `emulate mpi` and `dem profile --json` write
(schemas in the study-report brief, issue #15): each checks schema_version and kind and turns
the document into plain objects, so that a missing or mistyped field fails here, naming its
file and JSON path, and not halfway through a table."""
from types import SimpleNamespace

from .common import SchemaError, interval_object, items, load_kind, need, number, reading

THREAD_FIELDS = ("setup_s", "detect_s", "total_s")


def _validation_row(row, path, measured_key, estimate_key, error_key):
    return SimpleNamespace(measured=number(row, path, measured_key),
                           estimate=number(row, path, estimate_key),
                           file_error=number(row, path, error_key))


def thread_emulation(path):
    """emulation-threads.json: per variant the measured intervals, the emulated values at every
    thread count and the validation rows; the emulated chunk study."""
    document = load_kind(path, "contactlab-thread-emulation")
    with reading(path):
        scene = need(document, "$", "scene")
        variants = {}
        for vpath, v in items(document, "$", "variants"):
            name = need(v, vpath, "variant")
            measured = {}
            for mpath, m in items(v, vpath, "measured"):
                measured[number(m, mpath, "threads")] = {
                    f: interval_object(need(m, mpath, f), f"{mpath}.{f}") for f in THREAD_FIELDS}
            emulated = {}
            for epath, e in items(v, vpath, "emulated"):
                emulated[number(e, epath, "threads")] = {
                    f: number(e, epath, f) for f in THREAD_FIELDS + ("speedup", "imbalance")}
            validation = []
            for rpath, r in items(v, vpath, "validation"):
                threads = number(r, rpath, "threads")
                total = _validation_row(r, rpath, "measured_total_s", "emulated_total_s", "relative_error")
                detect = _validation_row(r, rpath, "measured_detect_s", "emulated_detect_s",
                                         "detect_relative_error")
                validation.append(SimpleNamespace(threads=threads, total=total, detect=detect))
            variants[name] = SimpleNamespace(measured=measured, emulated=emulated, validation=validation)
        chunk_study = []
        for cpath, c in items(document, "$", "chunk_study"):
            points = [(number(p, ppath, "chunk"), number(p, ppath, "detect_s"))
                      for ppath, p in items(c, cpath, "points")]
            # Optional (dynamic rows): the classic formulas' chunks, emulated.
            classic = [SimpleNamespace(name=need(k, kpath, "name"), chunk=number(k, kpath, "chunk"),
                                       detect_s=number(k, kpath, "detect_s"))
                       for kpath, k in (items(c, cpath, "classic") if "classic" in c else [])]
            chunk_study.append(SimpleNamespace(
                classic=classic,
                threads=number(c, cpath, "threads"), variant=need(c, cpath, "variant"),
                schedule=need(c, cpath, "schedule"), points=sorted(points),
                best_chunk=number(c, cpath, "best_chunk"), best_detect_s=number(c, cpath, "best_detect_s"),
                block_detect_s=number(c, cpath, "block_detect_s")))
        return SimpleNamespace(document=document, path=path, scene=scene,
                               method=need(document, "$", "method"),
                               measured_threads=need(document, "$", "measured_threads"),
                               variants=variants, chunk_study=chunk_study)


def mpi_model(path):
    """emulation-mpi.json: the model's series (speed-up and efficiency per process count) and
    its validation against measured runs."""
    document = load_kind(path, "contactlab-mpi-model")
    with reading(path):
        model = need(document, "$", "model")
        for key in ("latency_s", "bandwidth_bytes_per_s"):
            number(model, "$.model", key)
        # What every rank's loop costs however small its share (older files: none recorded).
        fixed = number(document, "$", "loop_fixed_s") if "loop_fixed_s" in document else 0.0
        series = []
        for spath, s in items(document, "$", "series"):
            points = []
            for ppath, p in items(s, spath, "points"):
                point = SimpleNamespace(**{k: number(p, ppath, k) for k in (
                    "processes", "ranks", "compute_s", "communication_s", "detect_s", "speedup",
                    "efficiency")})
                # Optional: (max - mean) / max of the ranks' loop times, where the file has it.
                point.rank_imbalance = number(p, ppath, "rank_imbalance") if "rank_imbalance" in p else None
                # Optional: the deal's locality factor in compute_s (files from before it have
                # none), and the replay before it: compute_s = fixed + factor (replay - fixed).
                point.locality = number(p, ppath, "locality_factor") if "locality_factor" in p else 1.0
                point.replay_compute_s = (fixed + (point.compute_s - fixed) / point.locality
                                          if point.locality > 0 else point.compute_s)
                # Optional: the slowest rank's loop timed alone on this machine (measured).
                point.slowest_measured = (interval_object(p["slowest_rank_measured_s"],
                                                          f"{ppath}.slowest_rank_measured_s")
                                          if "slowest_rank_measured_s" in p else None)
                points.append(point)
            series.append(SimpleNamespace(mode=need(s, spath, "mode"),
                                          threads_per_rank=number(s, spath, "threads_per_rank"),
                                          label=need(s, spath, "label"),
                                          points=sorted(points, key=lambda p: p.processes)))
        validation = []
        for rpath, r in items(document, "$", "validation"):
            row = _validation_row(r, rpath, "measured_detect_s", "predicted_detect_s", "relative_error")
            row.mode, row.ranks = need(r, rpath, "mode"), number(r, rpath, "ranks")
            row.threads_per_rank = number(r, rpath, "threads_per_rank")
            row.oversubscribed = need(r, rpath, "oversubscribed")
            if not isinstance(row.oversubscribed, bool):
                raise SchemaError(f"{rpath}.oversubscribed: expected true or false")
            validation.append(row)
        return SimpleNamespace(document=document, path=path, model=model,
                               variant=need(document, "$", "variant"),
                               scene=need(document, "$", "scene"), series=series, validation=validation)


PHASES = ("candidates_s", "pair_forces_s", "reduction_s", "wall_forces_s", "update_s", "integration_s")


def dem_profile(path):
    """dem-profile.json: the phase split at one thread, the serial fraction and its Amdahl
    bounds, the measured and emulated step times and the emulation's validation."""
    document = load_kind(path, "contactlab-dem-profile")
    with reading(path):
        split = {k: number(document, "$", "phase_split", k) for k in PHASES}
        bounds = {number(b, p, "threads"): number(b, p, "bound")
                  for p, b in items(document, "$", "amdahl_bound")}
        measured = {number(m, p, "threads"): SimpleNamespace(
            step=interval_object(need(m, p, "step_s"), f"{p}.step_s"), speedup=number(m, p, "speedup"))
            for p, m in items(document, "$", "measured")}
        emulated = {number(e, p, "threads"): SimpleNamespace(
            step_s=number(e, p, "step_s"), speedup=number(e, p, "speedup"))
            for p, e in items(document, "$", "emulated")}
        validation = []
        for p, r in items(document, "$", "validation"):
            row = _validation_row(r, p, "measured_step_s", "emulated_step_s", "relative_error")
            row.threads = number(r, p, "threads")
            validation.append(row)
        if 1 not in measured:
            raise SchemaError("$.measured: no entry at 1 thread (the speed-ups are over one thread)")
        return SimpleNamespace(
            document=document, path=path, config=need(document, "$", "config"),
            particles=number(document, "$", "particles"), variant=need(document, "$", "variant"),
            steps=number(document, "$", "steps"), rounds=number(document, "$", "rounds"),
            split=split, serial_fraction=number(document, "$", "serial_fraction"), bounds=bounds,
            measured=measured, emulated=emulated, validation=validation,
            method=need(document, "$", "method"))

"""The tuner's results (tuning/*.json, written by `contactlab tune --json`): model vs search vs
exhaustive at 2 threads, verified in random order, and the model's predictions for thread
counts this machine does not have."""
import os

from .common import (SchemaError, load_json, need, number, predicted, reading, table)


def load(tuning_dir):
    """{scene name: tuning document}, checked for the fields the report reads; {} when absent."""
    if not tuning_dir or not os.path.isdir(tuning_dir):
        return {}
    documents = {}
    for name in sorted(os.listdir(tuning_dir)):
        if not name.endswith(".json"):
            continue
        path = os.path.join(tuning_dir, name)
        t = load_json(path)
        with reading(path):
            if need(t, "$", "schema_version") != 1:
                raise SchemaError("$.schema_version: expected 1")
            need(t, "$", "scene", "kind")
            for i, m in enumerate(need(t, "$", "methods")):
                for key in ("method", "variant"):
                    need(m, f"$.methods[{i}]", key)
                number(m, f"$.methods[{i}]", "tuning_cost_s")
                _check_regrets(m, f"$.methods[{i}]")
                for j, st in enumerate(m.get("structures", [])):
                    need(st, f"$.methods[{i}].structures[{j}]", "variant")
                    _check_regrets(st, f"$.methods[{i}].structures[{j}]")
            for i, c in enumerate(need(t, "$", "classic")):
                for key in ("name", "inputs", "chunk"):
                    need(c, f"$.classic[{i}]", key)
                _check_regrets(c, f"$.classic[{i}]")
            for i, p in enumerate(t.get("predictions", [])):
                number(p, f"$.predictions[{i}]", "threads")
                number(p, f"$.predictions[{i}]", "predicted_s")
                need(p, f"$.predictions[{i}]", "variant")
        documents[name[:-5]] = t
    return documents


def _check_regrets(entry, path):
    """The optional measured median and regrets of a method or formula, where present."""
    if "measured" in entry:
        number(entry, path, "measured", "median_s")
    if "regret" in entry:
        number(entry, path, "regret")
        number(entry, path, "regret_ci95", 1)
    if "vs_exhaustive" in entry:
        number(entry, path, "vs_exhaustive", "ratio_minus_one")
        number(entry, path, "vs_exhaustive", "ci95", 1)


def _relative(entry, key, interval_key):
    """'+1.2% [-0.5, +3.0]' of a regret with its 95 % interval; '–' when absent."""
    if key not in entry:
        return "–"
    value = entry[key] if interval_key else entry[key]["ratio_minus_one"]
    ci = entry[interval_key] if interval_key else entry[key]["ci95"]
    return f"{100 * value:+.1f}% [{100 * ci[0]:+.1f}, {100 * ci[1]:+.1f}]"


def section(documents, out):
    out.append("\n## Tuning: model vs search vs exhaustive (2 threads)\n")
    if not documents:
        out.append("Not run (no tuning/*.json).")
        return
    out.append("T_c median and regret come from a final verification in which every distinct "
               "choice (the methods', the classic formulas' and the model's best schedule of each "
               "structure it priced, rows \"model: structure\") is timed once per round, in a new "
               "random order each round. Regret, as the files define it: " +
               "; ".join(sorted({str(t.get("verification", {}).get("regret_against", "not recorded"))
                                 for t in documents.values()})) +
               ". \"vs exhaustive\" = the median of the per-round ratios to the exhaustive best − 1 "
               "(the issue's target); brackets: 95% intervals. Cost = seconds the "
               "method spent choosing (the search's includes the screening and the model it is "
               "seeded by); timed runs = runs on the scene.\n")
    rows = []
    for scene, t in documents.items():
        rounds = t.get("verification", {}).get("rounds", "?")
        methods = t["methods"]
        exhaustive = next((m for m in methods if m["method"] == "exhaustive"), None)
        for m in methods:
            measured = m.get("measured", {})
            median = f"{measured['median_s']:.4f}" if measured else "–"
            rows.append([scene, m["method"], f"`{m['variant']}`", median,
                         _relative(m, "regret", "regret_ci95"), _relative(m, "vs_exhaustive", None),
                         f"{m['tuning_cost_s']:.1f}", m.get("timed_runs", "–")])
        model = next((m for m in methods if m["method"] == "model"), None)
        for st in (model or {}).get("structures", []):
            if "measured" not in st:
                continue
            rows.append([scene, "model: structure", f"`{st['variant']}`",
                         f"{st['measured']['median_s']:.4f}", _relative(st, "regret", "regret_ci95"),
                         "–", "–", "–"])
        for c in t["classic"]:
            median = c.get("measured", {}).get("median_s")
            rows.append([scene, f"classic: {c['name']} ({c['inputs']})", f"`{c.get('variant', c['chunk'])}`",
                         f"{median:.4f}" if median is not None else "–",
                         _relative(c, "regret", "regret_ci95"), _relative(c, "vs_exhaustive", None), "–", "–"])
        search = next((m for m in methods if m["method"] == "search"), None)
        if search and exhaustive and "chunk_search_cost_s" in search:
            rows.append([scene, "search / exhaustive cost", "", "", "", "",
                         f"{search['chunk_search_cost_s'] / exhaustive['tuning_cost_s']:.0%} (chunk search), "
                         f"{search['tuning_cost_s'] / exhaustive['tuning_cost_s']:.0%} (all of it)",
                         f"{search.get('chunk_search_timed_runs', '–')} / {exhaustive.get('timed_runs', '–')}"])
        rows.append([scene, "verification", "", "", f"{rounds} rounds", "", "", ""])
    out.extend(table(["scene", "method", "choice", "T_c median [s]", "regret [95% CI]",
                      "vs exhaustive [95% CI]", "cost [s]", "timed runs"], rows))


def predictions(documents):
    """[(scene, threads, variant, predicted_s)] of every tuning file."""
    return [(scene, p["threads"], p["variant"], p["predicted_s"])
            for scene, t in documents.items() for p in t.get("predictions", [])]


def predictions_table(documents, out):
    rows = [[scene, threads, f"`{variant}`", predicted(f"{seconds:.4f}")]
            for scene, threads, variant, seconds in predictions(documents)]
    if rows:
        out.append("\n**The tuner model's predictions for other thread counts** (predicted, not "
                   "measured):\n")
        out.extend(table(["scene", "threads", "predicted choice", "predicted T_c [s]"], rows))


def paper_scene(documents, scene):
    """The tuning run on the scene of the chunk study (same kind and N), else None."""
    for name, t in documents.items():
        s = t["scene"]
        if s.get("kind") == scene.get("kind") and s.get("n") == scene.get("n"):
            return name, t
    return None

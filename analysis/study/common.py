"""What every section of the report shares: strict reading of the result files (errors name the
file and the JSON path), the summaries and intervals they hold, the cell formats that mark
emulated and predicted values, and atomic writes."""
import contextlib
import json
import math
import os
import statistics
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)

# Footnote markers. Every emulated or predicted value in a table carries one, in italics.
EMULATED = "†"
PREDICTED = "§"
SHORT_INTERVAL = "‡"  # fewer than 6 samples: the interval is [min, max] and cannot reach 95 %
NATIVE_DIVISOR = "¶"  # Table 6: per test divided by the native run's tests (older files)

FOOTNOTE_EMULATED = (f"{EMULATED} emulated, not measured: `contactlab emulate threads` (and `dem "
                     "profile --emulate`) price the loop's exact work per iteration with costs "
                     "calibrated on this machine, scale it to the measured one-thread time and replay "
                     "it under the schedule at the requested thread count (docs/emulation.md; the "
                     "method is in the file). Cache sharing is not modelled; memory bandwidth only "
                     "where the file names a machine file (section \"Memory bandwidth\"). "
                     "At a measured thread count the emulated value is shown to validate it.")
FOOTNOTE_PREDICTED = (f"{PREDICTED} predicted: a performance model's value (emulation-mpi.json, "
                      "tuning/*.json), not a measurement.")
FOOTNOTE_SHORT = (f"{SHORT_INTERVAL} fewer than 6 repetitions: the interval is [min, max] and does "
                  "not reach 95 % coverage.")
WITHIN_TARGET = 0.10  # the relative error an emulation or model must stay within to count as validated


class SchemaError(Exception):
    """A result file that does not hold what the report reads: the message names the JSON path."""


def need(obj, path, *keys):
    """obj[keys[0]][keys[1]]..., or SchemaError naming the JSON path of the missing field."""
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


def number(obj, path, *keys):
    """need(), and the value must be a finite number (booleans are not)."""
    value = need(obj, path, *keys)
    where = path + "".join(f"[{k}]" if isinstance(k, int) else f".{k}" for k in keys)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != value \
            or value in (float("inf"), float("-inf")):
        raise SchemaError(f"{where}: expected a finite number, got {json.dumps(value)}")
    return value


def items(obj, path, *keys):
    """need(), and the value must be a list: [(path of the element, element), ...]."""
    value = need(obj, path, *keys)
    where = path + "".join(f".{k}" for k in keys)
    if not isinstance(value, list):
        raise SchemaError(f"{where}: expected a list")
    return [(f"{where}[{i}]", element) for i, element in enumerate(value)]


@contextlib.contextmanager
def reading(path):
    """Errors raised while a file's contents are read name that file first."""
    try:
        yield
    except SchemaError as error:
        if getattr(error, "located", False):
            raise
        located = SchemaError(f"{path}: {error}")
        located.located = True
        raise located from None


def load_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except json.JSONDecodeError as error:
        raise SchemaError(f"{path}: not JSON: {error}") from None


def load_kind(path, kind):
    """An emulation, model or profile file: schema_version 1 and the expected kind."""
    document = load_json(path)
    with reading(path):
        if need(document, "$", "schema_version") != 1:
            raise SchemaError("$.schema_version: expected 1")
        if need(document, "$", "kind") != kind:
            raise SchemaError(f"$.kind: expected {kind!r}, got {document['kind']!r}")
        need(document, "$", "context")
    return document


def load_results(path):
    """A result file (docs/result-schema.md), checked for the fields the report reads."""
    document = load_json(path)
    with reading(path):
        if need(document, "$", "schema_version") != 1:
            raise SchemaError("$.schema_version: expected 1")
        need(document, "$", "context")
        for where, run in items(document, "$", "runs"):
            for key in ("status", "parameters", "aggregates", "work", "counters"):
                need(run, where, key)
            need(run, where, "parameters", "variant")
            need(run, where, "parameters", "threads")
    return document


def optional(directory, name):
    """The path of an input of the report, or None when that step was not run."""
    path = os.path.join(directory, name)
    return path if os.path.exists(path) else None


@dataclass(frozen=True)
class Interval:
    median: float
    low: float
    high: float
    reached: bool = True  # False: fewer samples than the level needs, [min, max] instead

    def overlaps(self, other):
        return self.low <= other.high and other.low <= self.high


def summary(run, path, field):
    """aggregates.<field> of a run as an Interval (docs/result-schema.md, summary)."""
    s = need(run, path, "aggregates", field)
    where = f"{path}.aggregates.{field}"
    reached = need(s, where, "interval").get("reached_level", True)
    return Interval(number(s, where, "median"), number(s, where, "interval", "low"),
                    number(s, where, "interval", "high"), bool(reached))


def interval_object(obj, path):
    """The emulation files' {"median", "low", "high", "level"} as an Interval."""
    return Interval(number(obj, path, "median"), number(obj, path, "low"), number(obj, path, "high"))


def ratio_interval(numerator, denominator):
    """median ratio, and the conservative interval of a ratio of two independent medians:
    [num.low / den.high, num.high / den.low] (it holds both medians' 95 % intervals at once)."""
    return Interval(numerator.median / denominator.median, numerator.low / denominator.high,
                    numerator.high / denominator.low, numerator.reached and denominator.reached)


def median_interval(values, level=0.95):
    """The median and its distribution-free interval (order statistics of a binomial(n, 1/2)),
    as kernels/support/src/statistics.cpp computes it; reached is False where n is too small for
    the level (the interval is then [min, max])."""
    xs = sorted(values)
    n = len(xs)
    if n == 0:
        raise ValueError("median of no values")
    mid = n // 2
    med = xs[mid] if n % 2 else 0.5 * (xs[mid - 1] + xs[mid])
    pmf = [math.comb(n, i) / 2.0 ** n for i in range(n + 1)]
    k, below = 1, pmf[0]
    coverage = max(0.0, 1.0 - 2.0 * below)
    while 2 * (k + 1) <= n + 1:
        next_below = below + pmf[k]
        next_coverage = max(0.0, 1.0 - 2.0 * next_below)
        if next_coverage < level:
            break
        k, below, coverage = k + 1, next_below, next_coverage
    return Interval(med, xs[k - 1], xs[n - k], coverage >= level)


def round_medians(run, path, field):
    """{round: median of samples.<field> in that round} of a run a sweep measured in rounds
    (samples.round), or None when its samples carry no rounds."""
    rounds = need(run, path, "samples").get("round")
    if rounds is None:
        return None
    values = need(run, path, "samples", field)
    if len(rounds) != len(values):
        raise SchemaError(f"{path}.samples.round: {len(rounds)} entries for {len(values)} samples")
    by_round = {}
    for r, v in zip(rounds, values):
        by_round.setdefault(r, []).append(v)
    return {r: statistics.median(v) for r, v in by_round.items()}


def paired_ratio(numerator, denominator):
    """The median of the per-round ratios of two runs' round medians (round_medians), over the
    rounds both hold, with its 95 % interval: a slow spell of the machine slows both sides of a
    round's ratio. None when they share no round."""
    common = sorted(set(numerator) & set(denominator))
    if not common:
        return None
    return median_interval([numerator[r] / denominator[r] for r in common])


def run_ratio(numerator, denominator, numerator_rounds=None, denominator_rounds=None):
    """numerator / denominator of two runs' summaries (Interval): the median of the per-round
    ratios where both runs carry rounds (round_medians) and share some, else the conservative
    ratio of independent medians (ratio_interval)."""
    if numerator_rounds and denominator_rounds:
        paired = paired_ratio(numerator_rounds, denominator_rounds)
        if paired is not None:
            return paired
    return ratio_interval(numerator, denominator)


def ok_runs(document):
    """[(path, run)] of the runs whose status is ok."""
    return [(f"$.runs[{i}]", r) for i, r in enumerate(document["runs"]) if r["status"] == "ok"]


def runs_by_variant_threads(document):
    return {(r["parameters"]["variant"], r["parameters"]["threads"]): (path, r)
            for path, r in ok_runs(document)}


def num(x, digits=4):
    """A time or ratio with `digits` significant digits."""
    return f"{x:.{digits}g}"


def cell(value, digits=4):
    """'median [low, high]', marked when the interval is [min, max] of too few samples."""
    return (f"{num(value.median, digits)} [{num(value.low, digits)}, {num(value.high, digits)}]"
            + ("" if value.reached else SHORT_INTERVAL))


def speedup_cell(value):
    return (f"{value.median:.2f} [{value.low:.2f}, {value.high:.2f}]"
            + ("" if value.reached else SHORT_INTERVAL))


def emulated(text):
    return f"*{text}*{EMULATED}"


def predicted(text):
    return f"*{text}*{PREDICTED}"


def relative_error(estimate, measured):
    return (estimate - measured) / measured


def percent(x):
    return f"{100 * x:+.1f}%"


def context_line(document, path="$"):
    """'cpu, N cores; commit abcdef0123 (dirty); date' from a file's context."""
    ctx = need(document, path, "context")
    machine = need(ctx, f"{path}.context", "machine")
    build = need(ctx, f"{path}.context", "build")
    commit = str(build.get("git_commit", "?"))
    return (f"{str(machine.get('cpu_model', '?')).strip()}, {machine.get('cores', '?')} cores; "
            f"commit {commit[:10]}{' (dirty)' if build.get('git_dirty') else ''}; "
            f"{ctx.get('date_utc', '?')}")


def table(header, rows):
    """Markdown table lines."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return lines


def write_text_atomically(path, text):
    temporary = path + ".tmp"
    with open(temporary, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(temporary, path)


def save_figure(fig, figures_dir, name):
    """Writes figures_dir/name atomically; returns the link relative to the report."""
    os.makedirs(figures_dir, exist_ok=True)
    path = os.path.join(figures_dir, name)
    fig.tight_layout()
    fig.savefig(path + ".tmp", dpi=110, format="png")
    plt.close(fig)
    os.replace(path + ".tmp", path)
    return f"figures/{name}"

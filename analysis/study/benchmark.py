"""The kernel benchmark (Google Benchmark's JSON, benchmark.json): T_ALL per variant and the
speed targets of the foundation issue, as ratios within that one run."""
from .common import SchemaError, load_json, reading, table


def _google_benchmark(path, name, title, out):
    """Writes the section's title; returns Google Benchmark's JSON at path (file `name`) and its
    context, or None after "Not run" where the file is absent."""
    out.append(f"\n## {title}\n")
    if path is None:
        out.append(f"Not run (no {name}).")
        return None
    b = load_json(path)
    with reading(path):
        if not isinstance(b.get("benchmarks"), list):
            raise SchemaError("$.benchmarks: missing")
    return b, b.get("context", {})


def section(path, out):
    loaded = _google_benchmark(path, "benchmark.json", "Kernel benchmark (Google Benchmark, "
                               "N = 1,024,000, D = 1/200, clustered)", out)
    if loaded is None:
        return
    b, ctx = loaded
    with reading(path):
        out.append(f"{ctx.get('host_name', '?')}, {ctx.get('num_cpus', '?')} CPUs, {ctx.get('date', '?')}. "
                   "Time = T_ALL per iteration (manual time, mean of the iterations; Google "
                   "Benchmark gives no interval).\n")
        rows, by_name = [], {}
        for i, bm in enumerate(b["benchmarks"]):
            if bm.get("run_type") == "aggregate":
                continue
            for key in ("name", "real_time", "T_s", "T_c", "tests_per_s", "contacts_per_s"):
                if key not in bm:
                    raise SchemaError(f"$.benchmarks[{i}].{key}: missing")
            # The dense cell index is what the paper's scene uses (grid=auto picks it there).
            name = bm["name"].replace("detect/", "").replace("/manual_time", "").replace("/grid=dense", "")
            by_name[name] = bm
            rows.append([f"`{name}`", f"{bm['real_time']:.1f}", f"{1e3 * bm['T_s']:.1f}",
                         f"{1e3 * bm['T_c']:.1f}", f"{bm['tests_per_s']:.3g}", f"{bm['contacts_per_s']:.3g}"])
    out.extend(table(["benchmark", "T_ALL [ms]", "T_s [ms]", "T_c [ms]", "tests/s", "contacts/s"], rows))

    def time_of(name):
        bm = by_name.get(name)
        return bm["real_time"] if bm else None

    claims = []
    u, s = time_of("particle/unsorted/full/static/threads:1"), time_of("particle/sorted/full/static/threads:1")
    if u and s:
        claims.append(f"reordering: particle/unsorted / particle/sorted T_ALL = **{u / s:.2f}x** (target >= 3x)")
    h = time_of("particle/sorted/half/static/threads:1")
    if s and h:
        claims.append(f"half stencil: full / half T_ALL (sorted, static) = **{s / h:.2f}x** (target >= 1.4x)")
    serial = by_name.get("particle/sorted/full/static/threads:1")
    if serial:
        claims.append(f"T_s of 1,024,000 particles, sorted, 1 thread = **{1e3 * serial['T_s']:.1f} ms** (target < 60 ms)")
    if claims:
        out.append("\nSpeed targets (ratios within this one benchmark run, 1 thread):\n")
        out.extend(f"- {c}" for c in claims)


def search_section(path, out):
    """The detector against nanoflann's k-d tree (neighbour-search.json: Google Benchmark,
    random interleaving, medians over repetitions): T_ALL and the ratio per thread count."""
    loaded = _google_benchmark(path, "neighbour-search.json",
                               "Against nanoflann (k-d tree radius search, N = 1,024,000, "
                               "D = 1/200, clustered)", out)
    if loaded is None:
        return
    b, ctx = loaded
    with reading(path):
        if str(ctx.get("rows_differing_from_nanoflann")) != "0":
            raise SchemaError("$.context.rows_differing_from_nanoflann: not 0 (the contact lists differ)")
        medians = {}
        for i, bm in enumerate(b["benchmarks"]):
            if bm.get("aggregate_name") != "median":
                continue
            for key in ("run_name", "real_time", "build_or_T_s", "search_or_T_c", "repetitions"):
                if key not in bm:
                    raise SchemaError(f"$.benchmarks[{i}].{key}: missing")
            medians[bm["run_name"].replace("/manual_time", "")] = bm
        if not medians:
            raise SchemaError("$.benchmarks: no median aggregates (run with --benchmark_repetitions)")
    reps = min(bm["repetitions"] for bm in medians.values())
    out.append(f"{ctx.get('host_name', '?')}, {ctx.get('num_cpus', '?')} CPUs, {ctx.get('date', '?')}, "
               f"commit `{str(ctx.get('git_commit', '?'))[:10]}`; nanoflann {ctx.get('nanoflann_version', '?')}, "
               f"detector `{ctx.get('detector_variant', '?')}`. Medians of {reps} repetitions in one "
               "randomly interleaved run; both write every particle's partner row, and the two "
               "contact lists were compared row by row before timing: **0 rows differ**.\n")
    rows = []
    for name, bm in sorted(medians.items()):
        rows.append([f"`{name.replace('search/', '')}`", f"{bm['real_time']:.1f}",
                     f"{1e3 * bm['build_or_T_s']:.1f}", f"{1e3 * bm['search_or_T_c']:.1f}"])
    out.extend(table(["benchmark", "total [ms]", "build / T_s [ms]", "search / T_c [ms]"], rows))
    claims = []
    for name, ours in sorted(medians.items()):
        if not name.startswith("search/contactlab/"):
            continue
        threads = name.rsplit("/", 1)[1]
        theirs = [bm for n, bm in medians.items() if n.startswith("search/nanoflann/" + threads + "/")]
        if theirs:
            best = min(theirs, key=lambda bm: bm["real_time"])
            claims.append(f"{threads.replace(':', ' ')}: nanoflann's best leaf size "
                          f"({best['run_name'].rsplit(':', 1)[1].replace('/manual_time', '')}) / contactlab "
                          f"= **{best['real_time'] / ours['real_time']:.1f}x**")
    if claims:
        out.append("\nThe ratio of medians (nanoflann's build is serial in 1.4):\n")
        out.extend(f"- {c}" for c in claims)

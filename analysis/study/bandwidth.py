"""The thread emulation priced by its bytes (`emulate threads --machine`, docs/emulation.md
"Bandwidth"): each variant's bytes by phase and, at the most threads emulated, the bandwidth
its threads draw, the time its bytes need there and the emulated T_ALL beside it."""
from .common import emulated, items, load_kind, need, num, number, optional, reading, table

# The study's own emulation, else the one made apart for the bandwidth.
FILES = ("emulation-threads.json", "emulation-threads-bandwidth.json")


def _priced(results_dir):
    for name in FILES:
        path = optional(results_dir, name)
        if path:
            document = load_kind(path, "contactlab-thread-emulation")
            if document.get("bandwidth"):
                return name, path, document
    return None


def section(results_dir, out):
    out.append("\n## Memory bandwidth in the thread emulation\n")
    found = _priced(results_dir)
    if found is None:
        out.append("Not run (no thread emulation priced by bytes: `emulate threads --machine`).")
        return
    name, path, document = found
    with reading(path):
        b = need(document, "$", "bandwidth")
        ceiling = number(b, "$.bandwidth", "ceiling_bytes_per_s")
        beyond = (f"towards {ceiling / 1e9:.0f} GB/s ({need(b, '$.bandwidth', 'ceiling_source')})"
                  if ceiling > 0 else "the last probed bandwidth (no ceiling stated)")
        out.append(f"`{name}`: every phase takes at least its bytes (counted from the exact work "
                   f"and the data layout) over the bandwidth its threads draw, from the machine file "
                   f"`{need(b, '$.bandwidth', 'machine_file')}` and beyond its thread counts {beyond}. "
                   "*Bytes' time* is all the variant's bytes over that bandwidth: where it nears the "
                   "emulated T_ALL, memory decides.\n")
        rows = []
        for vpath, v in items(document, "$", "variants"):
            traffic = need(v, vpath, "traffic")
            points = [p for _, p in items(v, vpath, "emulated")]
            last = max(points, key=lambda p: p["threads"])
            gb = lambda key: f"{number(traffic, f'{vpath}.traffic', key) / 1e9:.3g}"  # noqa: E731
            rows.append([f"`{need(v, vpath, 'variant')}`", gb("setup_bytes"), gb("loop_bytes"),
                         gb("rows_bytes"), last["threads"],
                         emulated(f"{number(last, vpath, 'bytes_per_s') / 1e9:.0f}"),
                         emulated(num(number(last, vpath, "memory_s"))),
                         emulated(num(last["setup_s"] + last["detect_s"])),
                         f"{number(last, vpath, 'memory_s') / (last['setup_s'] + last['detect_s']):.0%}"])
    out.extend(table(["variant", "setup [GB]", "loop [GB]", "rows [GB]", "threads",
                      "bandwidth [GB/s]", "bytes' time [s]", "T_ALL [s]", "bytes' time / T_ALL"],
                     rows))

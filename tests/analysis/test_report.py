#!/usr/bin/env python3
"""analysis/report.py on the synthetic fixture (tests/analysis/fixture/synthetic-2c, hand-made
numbers): the tables hold the fixture's medians and intervals, emulated and predicted values
are marked, validation errors are computed from the two values, the figures exist, and a
malformed file stops the report with one line naming the file and the JSON path.

Run: /usr/bin/python3 tests/analysis/test_report.py   (CTest: analysis_report, label analysis).
Exits 77 (CTest's SKIP_RETURN_CODE) when this Python has no matplotlib."""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

SKIP = 77
ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
REPORT = os.path.join(ROOT, "analysis", "report.py")
FIXTURE = os.path.join(ROOT, "tests", "analysis", "fixture", "synthetic-2c")


def run_report(directory):
    return subprocess.run([sys.executable, REPORT, directory], capture_output=True, text=True, timeout=300)


class ReportOnFixture(unittest.TestCase):
    """One report of the whole fixture, read by every test of this class."""

    @classmethod
    def setUpClass(cls):
        cls.temporary = tempfile.mkdtemp(prefix="contactlab-report-")
        cls.results = os.path.join(cls.temporary, "synthetic-2c")
        shutil.copytree(FIXTURE, cls.results)
        # Pictures beside the machine folder, as results/dem/pit/hopper-small holds them; the
        # captions give the times, out of name order on purpose.
        pit = os.path.join(cls.temporary, "dem", "pit", "hopper-small")
        os.makedirs(pit)
        for name in ("b_section.png", "a_section.png"):
            with open(os.path.join(pit, name), "wb") as f:
                f.write(b"\x89PNG\r\n\x1a\n")  # only linked, never read
        with open(os.path.join(pit, "pictures.json"), "w") as f:
            json.dump({"pictures": {"a_section.png": "t = 2.50 s: the crater", "b_section.png": "t = 0.70 s: the channel"}}, f)
        # A Beverloo study of three fills, as scripts/beverloo writes it (values made up).
        beverloo = os.path.join(cls.temporary, "dem", "beverloo")
        os.makedirs(beverloo)
        with open(os.path.join(beverloo, "beverloo.json"), "w") as f:
            json.dump({"schema_version": 2, "setup": {"seeds": [1, 2, 3]},
                       "fit": {"C": 0.588, "k": 1.92, "r_squared": 0.9991,
                               "C_interval": [0.55, 0.62], "k_interval": [1.7, 2.1]},
                       "targets": {"C": [0.5, 0.65], "k": [1.0, 2.5]}, "in_target": True,
                       "orifices": [{"orifice_over_d": 6.0, "rate_kg_s": 0.0898,
                                     "rate_interval_kg_s": [0.08, 0.1],
                                     "seed_rates_kg_s": [0.08, 0.09, 0.1], "steady": False,
                                     "in_fit": True}]}, f)
        # The same emulation on two more core radii (the scene-law section compares them).
        with open(os.path.join(FIXTURE, "emulation-threads.json")) as f:
            base = json.load(f)
        cls.core_speedups = {}
        for core, slower in ((1, 1.0), (3, 0.5)):
            document = json.loads(json.dumps(base))
            document["scene"]["core"] = core
            for v in document["variants"]:
                for e in v["emulated"]:
                    e["detect_s"] *= slower
                one = next(m for m in v["measured"] if m["threads"] == 1)["detect_s"]["median"]
                sixteen = next(e for e in v["emulated"] if e["threads"] == 16)["detect_s"]
                cls.core_speedups[(core, v["variant"])] = one / sixteen
            with open(os.path.join(cls.results, f"emulation-threads-core-{core}.json"), "w") as f:
                json.dump(document, f)
        # The classic formulas in the emulated chunk study (dynamic rows).
        threads_path = os.path.join(cls.results, "emulation-threads.json")
        with open(threads_path) as f:
            emulation = json.load(f)
        for c in emulation["chunk_study"]:
            if c["schedule"] == "dynamic":
                c["classic"] = [{"name": "factoring", "chunk": 512, "detect_s": 1.25 * c["best_detect_s"]}]
        # Priced by bytes (emulate threads --machine): 10 GB of loop at 50 GB/s at 16 threads.
        emulation["bandwidth"] = {"machine_file": "machine.json", "ceiling_bytes_per_s": 8e10,
                                  "ceiling_source": "a stated figure"}
        for v in emulation["variants"]:
            v["traffic"] = {"setup_bytes": 1e8, "loop_bytes": 1e10, "rows_bytes": 2e8,
                            "offsets_bytes": 8e6, "footprint_bytes": 6e7, "working_set_bytes": 67108864}
            for e in v["emulated"]:
                e["bytes_per_s"] = 5e10 if e["threads"] == 16 else 2e10
                e["memory_s"] = 1.03e10 / e["bytes_per_s"]
        with open(threads_path, "w") as f:
            json.dump(emulation, f)
        # The pure-MPI series' slowest rank timed alone (emulate mpi writes it at every count).
        mpi_path = os.path.join(cls.results, "emulation-mpi.json")
        with open(mpi_path) as f:
            model = json.load(f)
        for p in model["series"][0]["points"]:
            t = 0.2 / p["processes"] ** 0.75
            p["slowest_rank"] = 0
            p["slowest_rank_measured_s"] = {"median": t, "low": 0.9 * t, "high": 1.1 * t,
                                            "level": 0.95, "repetitions": 7}
            # At 512 a locality factor as emulate mpi now writes it: compute_s holds it, and the
            # report shows the replay before it (fixed cost 1e-4 s untouched).
            if p["processes"] == 512:
                p["locality_factor"] = 1.5
        model["loop_fixed_s"] = 1e-4
        with open(mpi_path, "w") as f:
            json.dump(model, f)
        cls.process = run_report(cls.results)
        path = os.path.join(cls.results, "report.md")
        cls.report = open(path, encoding="utf-8").read() if os.path.exists(path) else ""

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.temporary)

    def section(self, title, until="\n## "):
        """The report from `title` to the next `until` (the next section by default)."""
        start = self.report.index(title)
        end = self.report.find(until, start + 1)
        return self.report[start:end if end >= 0 else None]

    def row(self, text, first_cells):
        """The table row of `text` that starts with these cells."""
        prefix = "| " + " | ".join(first_cells) + " |"
        rows = [line for line in text.splitlines() if line.startswith(prefix)]
        self.assertEqual(len(rows), 1, f"one row starting {prefix!r} in:\n{text}")
        return [c.strip() for c in rows[0].strip("|").split("|")]

    def test_succeeds(self):
        self.assertEqual(self.process.returncode, 0, self.process.stderr)

    def test_header_names_machine_and_commit(self):
        self.assertIn("**Machine:** Synthetic CPU, 2 cores", self.report)
        self.assertIn("`0123456789`", self.report)  # 10 characters of the commit
        self.assertNotIn("0123456789a", self.report)

    def test_measured_cells_hold_median_and_interval(self):
        table4 = self.section("**Table 4**", until="**Table 5**")
        self.assertIn("ours T_ALL [95 %]", table4)
        self.assertIn("ours speedup [95 %]", table4)
        # samples 0.50..0.56: median 0.53, interval [min, max] (7 samples reach 95 %)
        self.assertEqual(self.row(table4, ["1", "2.005"])[3], "0.53 [0.5, 0.56]")
        # speed-up at 2: 0.53 / 0.30, conservatively [0.50 / 0.33, 0.56 / 0.27]
        self.assertEqual(self.row(table4, ["2", "0.971"])[4], "1.77 [1.52, 2.07]")

    def test_emulated_cells_are_italic_with_marker_and_validated(self):
        table4 = self.section("**Table 4**", until="**Table 5**")
        row4 = self.row(table4, ["4", "0.583"])
        self.assertEqual(row4[3], "*0.15*†")
        self.assertEqual(row4[4], "*3.53*†")  # the file's speed-up 0.53 / 0.15
        row2 = self.row(table4, ["2", "0.971"])
        self.assertEqual(row2[5], "*0.318*†")
        self.assertEqual(row2[6], "+6.0%")  # (0.318 - 0.30) / 0.30
        self.assertIn("† emulated, not measured", table4 + self.section("## Tables 2"))

    def test_table6_gives_misses_per_test_beside_the_rates(self):
        table6 = self.section("## Table 6", until="## Fig. 8")
        # particle/unsorted: (540e6 + 4e6) L1 misses / 170e6 tests recorded by the simulated run
        # = 3.200; (850e6 + 224e6) accesses / 170e6 = 6.32; per particle 544e6 / 1,024,000.
        self.assertEqual(self.row(table6, ["`particle/unsorted/full/static`", "43.89", "14"])[3:],
                         ["50.652", "18.715", "6.32", "3.200", "531.2", "196.29", "simulated:fx10"])
        # particle/sorted predates the simulated run's own count: the native run's 179e6 (tiled),
        # marked.
        sorted_row = self.row(table6, ["`particle/sorted/full/static`", "4.545", "0.414"])
        self.assertEqual(sorted_row[5:8], ["4.63¶", "0.128¶", "22.5"])
        self.assertIn("¶ divided by the native run's candidate tests", table6)
        self.assertEqual(self.row(table6, ["`cell/sorted/full/static`", "3.982", "0.375"])[6], "0.129")

    def test_table6_explains_what_compares(self):
        table6 = self.section("## Table 6", until="## Fig. 8")
        self.assertIn("**How to read it.**", table6)
        self.assertIn("simulated `simd_target` off", table6)
        self.assertIn("3.200 L1 misses per test unsorted against 0.128 sorted: unsorted / sorted = 24.90 "
                      "(the paper's L1 rate ratio: 9.7)", table6)
        self.assertIn("Reordering cuts the L1 misses per test of both loops", table6)
        self.assertNotIn("set conflict", table6)

    def test_headline_marks_sixteen_threads_emulated(self):
        headline = self.section("## Headline")
        self.assertEqual(self.row(headline, ["16", "0.124"])[3:], ["*0.0375*†", "*14.40*†"])
        self.assertEqual(self.row(headline, ["2", "0.958"])[3], "0.28 [0.25, 0.31]")
        self.assertIn("`dynamic,4096`", headline)

    def test_validation_errors_computed_from_values(self):
        validation = self.section("## Validation")
        t_c = self.row(validation, ["threads", "`particle/sorted/full/static`, 2 threads, T_c"])
        self.assertEqual(t_c[2:], ["0.25", "*0.2*†", "-20.0%", "**no**"])
        dem = self.row(validation, ["DEM", "hopper-small, 2 threads, step"])
        self.assertEqual(dem[4:], ["+8.0%", "yes"])
        mpi = [line for line in validation.splitlines() if line.startswith("| MPI |") and "4 rank" in line]
        self.assertEqual(len(mpi), 1)
        self.assertIn("oversubscribed", mpi[0])
        self.assertIn("+25.0%", mpi[0])

    def test_mpi_table_is_predicted(self):
        mpi = self.section("## Figs. 9–10")
        row = self.row(mpi, ["1024", "pure MPI 682x, hybrid 833x"])
        self.assertTrue(all(c.startswith("*") and c.endswith("*§") for c in row[2:]), row)
        self.assertIn("§ predicted", mpi)
        self.assertIn("**oversubscribed**", mpi)

    def test_mpi_legends_say_predicted(self):
        sys.path.insert(0, os.path.join(ROOT, "analysis"))
        from study import inputs, mpi
        legends = []

        def capture(fig, figures_dir, name):
            legends.extend(t.get_text() for t in fig.axes[0].get_legend().get_texts())
            return name

        model = inputs.mpi_model(os.path.join(FIXTURE, "emulation-mpi.json"))
        original, mpi.save_figure = mpi.save_figure, capture
        try:
            with open(os.path.join(ROOT, "analysis", "data", "takagi2013.json")) as f:
                mpi._figures(model, json.load(f)["mpi"], self.temporary)
        finally:
            mpi.save_figure = original
        series = [text for text in legends if not text.startswith(("paper", "ideal"))]
        self.assertEqual(len(series), 2 * len(model.series))
        self.assertTrue(all(text.endswith("predicted (model)") for text in series), series)

    def test_chunk_study_claims_only_separated_intervals(self):
        chunk = self.section("## The open problem", until="## Otsuka")
        self.assertIn("Really slower (no overlap): k = 1.", chunk)
        self.assertIn("not a real difference (intervals overlap)", chunk)
        self.assertIn("*1024*†", chunk)  # emulated best chunk at 4 threads

    def test_dem_section(self):
        dem = self.section("## Otsuka")
        self.assertEqual(self.row(dem, ["contact force"])[1:3], ["80%", "80.0%"])
        self.assertEqual(self.row(dem, ["2", "0.0055 [0.0054, 0.0057]"])[2], "1.82 [1.72, 1.89]")
        self.assertEqual(self.row(dem, ["8", "*0.0021*†"])[2], "*4.76*†")
        # the pictures in time order, linked relative to the report
        crater, channel = dem.index("(../dem/pit/hopper-small/a_section.png)"), dem.index("b_section.png")
        self.assertLess(channel, crater)

    def test_beverloo_gives_intervals_over_the_fills(self):
        dem = self.section("## Otsuka")
        self.assertIn("C = 0.588, k = 1.92 (95 % interval over 3 fills: C 0.550 – 0.620, "
                      "k 1.70 – 2.10)", dem)
        self.assertEqual(self.row(dem, ["6.0"])[1:], ["0.0898", "0.08 – 0.1", "3", "no", "yes"])

    def test_scene_law_compares_core_radii_at_sixteen_threads(self):
        text = self.section("## Which clustering")
        self.assertIn("| variant | paper (T_ALL) | c = 1 | c = 3 |", text)
        cells = self.row(text, ["Table 4: `particle/sorted/full/static`"])
        self.assertEqual(cells[1], "13.28")
        self.assertEqual(cells[2], f"*{self.core_speedups[(1, 'particle/sorted/full/static')]:.2f}*†")
        self.assertEqual(cells[3], f"*{self.core_speedups[(3, 'particle/sorted/full/static')]:.2f}*†")
        self.assertEqual(self.row(text, ["Table 5: `cell/sorted/full/static`"])[2], "–")  # not emulated
        self.assertIn("closest core radius", text)

    def test_slowest_rank_alone_is_measured_with_its_speedup(self):
        text = self.section("**Pure MPI, the compute measured:**", until="**Validation**")
        cells = self.row(text, ["1024"])
        t = 0.2 / 1024 ** 0.75
        self.assertEqual(cells[1], f"{t:.4g} [{0.9 * t:.4g}, {1.1 * t:.4g}]")
        self.assertTrue(cells[2].endswith("§"), cells)  # the model's replay: predicted
        self.assertEqual(cells[4], "1.00")  # no locality factor in this point
        self.assertEqual(cells[5], f"{1024 ** 0.75:.1f}")  # 0.2 / t
        self.assertIn("gives 181x on our scene against the paper's 682x", text)
        # With a factor the replay is the compute before it: fixed + (compute - fixed) / factor.
        cells = self.row(text, ["512"])
        self.assertEqual(cells[4], "1.50")
        self.assertEqual(cells[2], f"*{1e-4 + (0.000878906 - 1e-4) / 1.5:.4g}*§")

    def test_classic_formulas_beside_the_emulated_best_chunk(self):
        text = self.section("**Best chunk at more threads", until="**The tuner model's predictions")
        self.assertIn("classic formulas (dynamic,k) over the best", text)
        rows = [line for line in text.splitlines() if "| dynamic |" in line]
        self.assertTrue(rows, text)
        for line in rows:
            self.assertIn("factoring k = 512: *+25.0%*†", line)

    def test_against_nanoflann_gives_the_ratio_of_medians(self):
        self.assertIn("**0 rows differ**", self.report)
        # The fixture's best leaf size at each thread count against the detector's median.
        self.assertIn("threads 1: nanoflann's best leaf size (24) / contactlab = **20.0x**", self.report)
        self.assertIn("threads 2: nanoflann's best leaf size (24) / contactlab = **26.4x**", self.report)

    def test_bandwidth_gives_each_variants_bytes_beside_its_time(self):
        text = self.section("## Memory bandwidth in the thread emulation")
        self.assertIn("towards 80 GB/s (a stated figure)", text)
        self.assertIn("`machine.json`", text)
        with open(os.path.join(self.results, "emulation-threads.json")) as f:
            v = json.load(f)["variants"][0]
        last = max(v["emulated"], key=lambda e: e["threads"])
        cells = self.row(text, [f"`{v['variant']}`"])
        self.assertEqual(cells[1:6], ["0.1", "10", "0.2", "16", "*50*†"])
        self.assertEqual(cells[6], f"*{0.206:.4g}*†")
        self.assertEqual(cells[8], f"{0.206 / (last['setup_s'] + last['detect_s']):.0%}")

    def test_figures_exist(self):
        for name in ("fig8_speedup.png", "fig9_mpi_speedup.png", "fig10_mpi_efficiency.png",
                     "chunk_study.png", "dem_speedup.png"):
            path = os.path.join(self.results, "figures", name)
            self.assertTrue(os.path.getsize(path) > 1000, path)
            self.assertIn(f"(figures/{name})", self.report)
        self.assertFalse([n for n in os.listdir(os.path.join(self.results, "figures")) if n.endswith(".tmp")])


class SweepsInRounds(unittest.TestCase):
    """Sweeps run in rounds: differences and speed-ups from the rounds' paired ratios."""

    @classmethod
    def setUpClass(cls):
        temporary = tempfile.mkdtemp(prefix="contactlab-rounds-")
        try:
            results = os.path.join(temporary, "synthetic-2c")
            shutil.copytree(FIXTURE, results)
            # Every run's i-th sample in round i: the fixture's samples rise together, as a spell
            # of the machine would make them.
            for name in ("chunk-study.json", "paper-tables.json"):
                path = os.path.join(results, name)
                with open(path) as f:
                    document = json.load(f)
                for run in document["runs"]:
                    run["samples"]["round"] = list(range(len(run["samples"]["total_s"])))
                with open(path, "w") as f:
                    json.dump(document, f)
            cls.process = run_report(results)
            with open(os.path.join(results, "report.md")) as f:
                cls.report = f.read()
        finally:
            shutil.rmtree(temporary)

    def test_succeeds(self):
        self.assertEqual(self.process.returncode, 0, self.process.stderr)

    def test_paired_rounds_separate_what_overlapping_intervals_cannot(self):
        # dynamic,64 runs 4.2 % behind dynamic,4096 in every round, their intervals overlap.
        self.assertIn("the sweep ran in 7 rounds", self.report)
        self.assertIn("Really slower (ratio's interval above 1): k = 1, 64.", self.report)
        self.assertIn("(median of 7 rounds' ratios)", self.report)

    def test_speedups_are_medians_of_the_rounds_ratios(self):
        table4 = self.report[self.report.index("**Table 4**"):self.report.index("**Table 5**")]
        row = [line for line in table4.splitlines() if line.startswith("| 2 | 0.971 |")]
        # rounds' ratios 0.50 / 0.27 .. 0.56 / 0.33: median 0.53 / 0.30, interval their extremes
        self.assertEqual(row[0].split("|")[5].strip(), "1.77 [1.70, 1.85]")


class ReportOnDamagedInput(unittest.TestCase):
    def setUp(self):
        self.temporary = tempfile.mkdtemp(prefix="contactlab-report-")
        self.results = os.path.join(self.temporary, "m")
        shutil.copytree(FIXTURE, self.results)

    def tearDown(self):
        shutil.rmtree(self.temporary)

    def edit(self, name, change):
        path = os.path.join(self.results, name)
        with open(path) as f:
            document = json.load(f)
        change(document)
        with open(path, "w") as f:
            json.dump(document, f)

    def assert_fails_naming(self, *words):
        process = run_report(self.results)
        self.assertEqual(process.returncode, 1, process.stdout + process.stderr)
        lines = process.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, process.stderr)
        for word in words:
            self.assertIn(word, lines[0])
        self.assertFalse(os.path.exists(os.path.join(self.results, "report.md")))

    def test_missing_field_names_file_and_path(self):
        self.edit("emulation-threads.json", lambda d: d["variants"][0]["emulated"][2].pop("total_s"))
        self.assert_fails_naming("emulation-threads.json", "$.variants[0].emulated[2].total_s")

    def test_missing_aggregate_names_run(self):
        self.edit("paper-tables.json", lambda d: d["runs"][1]["aggregates"]["total_s"].pop("median"))
        self.assert_fails_naming("paper-tables.json", "$.runs[1].aggregates.total_s.median")

    def test_differing_contact_lists_fail(self):
        self.edit("neighbour-search.json",
                  lambda d: d["context"].update(rows_differing_from_nanoflann="3"))
        self.assert_fails_naming("neighbour-search.json", "$.context.rows_differing_from_nanoflann")

    def test_wrong_kind(self):
        self.edit("dem-profile.json", lambda d: d.update(kind="something-else"))
        self.assert_fails_naming("dem-profile.json", "$.kind")

    def test_not_json(self):
        with open(os.path.join(self.results, "emulation-mpi.json"), "w") as f:
            f.write("{ not json")
        self.assert_fails_naming("emulation-mpi.json", "not JSON")

    def test_table6_explains_a_set_conflict_where_sorted_misses_as_often(self):
        def conflicted(document):
            for run in document["runs"]:
                if run["parameters"]["variant"] == "cell/sorted/full/static":
                    for event in run["counters"][1]["events"]:
                        if event["name"] == "D1mr":
                            event["total"] = 510000000  # 3 misses per test, as before the fix
        self.edit("table6-cache.json", conflicted)
        process = run_report(self.results)
        self.assertEqual(process.returncode, 0, process.stderr)
        with open(os.path.join(self.results, "report.md")) as f:
            report = f.read()
        self.assertIn("reordering does not cut the cell loop's L1 misses per test", report)
        self.assertIn("a set conflict, not an effect of reordering", report)

    def test_table6_simulated_record_without_events_names_the_path(self):
        self.edit("table6-cache.json", lambda d: d["runs"][0]["counters"][1]["events"].pop(3))
        self.assert_fails_naming("table6-cache.json", "$.runs[0].counters[1].events", "D1mr")

    def test_missing_optional_input_says_not_run(self):
        os.remove(os.path.join(self.results, "emulation-mpi.json"))
        process = run_report(self.results)
        self.assertEqual(process.returncode, 0, process.stderr)
        with open(os.path.join(self.results, "report.md")) as f:
            report = f.read()
        self.assertIn("Not run (no emulation-mpi.json).", report)


if __name__ == "__main__":
    if importlib.util.find_spec("matplotlib") is None:
        print(f"skipped: {sys.executable} has no matplotlib (Debian: apt-get install python3-matplotlib)")
        sys.exit(SKIP)
    unittest.main()

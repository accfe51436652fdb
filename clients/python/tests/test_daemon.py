"""Every Bench command against a real hystbenchd on the loopback actuator.

Two daemons: one on the wall clock that never gets a model (errors that need its absence, runs
without a model, uploads, stop and abort of a running run), and one on the simulated clock that
identifies once in setUpClass for what needs a model (figures, not timing, are under test there).
"""

from __future__ import annotations

import json
import math
import os
import unittest
from typing import Any, Dict, List, Tuple

import _support
from hystbench import Bench, BenchError, RunEndedError, RunResult, SweepResult, read_run

RATE_HZ = 10000.0  # config/loopback.toml's loop rate


def rms_and_max(log: Any, start: int) -> Tuple[float, float]:
    error = [y - yr for y, yr in zip(log["y"][start:], log["yr"][start:])]
    return math.sqrt(sum(e * e for e in error) / len(error)), max(abs(e) for e in error)


def ramps(points: List[Tuple[float, float]], rate_hz: float) -> List[float]:
    """Straight lines through (time [s], value) points, sampled at rate_hz."""
    out: List[float] = []
    for (t0, v0), (t1, v1) in zip(points, points[1:]):
        n = int(round((t1 - t0) * rate_hz))
        out += [v0 + (v1 - v0) * k / n for k in range(n)]
    out.append(points[-1][1])
    return out


class WithoutModelTest(_support.DaemonTestCase):
    @classmethod
    def setUpClass(cls) -> None:
        cls.daemon = _support.Daemon("hbpy-a")

    def test_greeting_status_config_and_model_list(self) -> None:
        self.assertEqual(self.bench.greeting["hello"], "hystbenchd")
        self.assertEqual(self.bench.protocol, 1)
        status = self.bench.status()
        self.assertIn(status["state"], ("idle", "running"))
        self.assertIsNone(status["model"])
        config = self.bench.config_get()
        self.assertEqual(config["loop"]["rate_hz"], RATE_HZ)
        self.assertEqual(config["daemon"]["socket_path"], self.daemon.socket)
        self.assertEqual(config["identify"]["settle_s"], 0.0)
        self.assertEqual(config["loop"]["clock"], "wall")
        self.assertEqual(status["loop"]["clock"], "wall")
        models = self.bench.model_list()
        self.assertEqual(models["models"], [])
        self.assertEqual(models["folder"], str(self.daemon.model_dir))

    def test_errors_carry_the_daemons_code_and_message(self) -> None:
        def code(call: Any) -> str:
            with self.assertRaises(BenchError) as caught:
                call()
            self.assertTrue(caught.exception.message)
            return caught.exception.code

        self.assertEqual(code(lambda: self.bench.track(compensator="inverse")), "no_model")
        self.assertEqual(code(lambda: self.bench.model_get()), "no_model")
        self.assertEqual(code(lambda: self.bench.track(frequency_hz="fast")), "bad_params")
        self.assertEqual(code(lambda: self.bench.track(speed=3)), "bad_params")
        self.assertEqual(
            code(lambda: self.bench.track(min_um=-500.0, max_um=10.0)), "out_of_range"
        )
        self.assertEqual(code(lambda: self.bench.identify(model="spline")), "bad_params")
        self.assertEqual(code(lambda: self.bench.model_load(stored="nothing-here")), "bad_params")
        self.assertEqual(code(lambda: self.bench.model_load({"schema": "nope"})), "bad_model")
        self.assertEqual(code(lambda: self.bench.request("fly")), "unknown_command")
        with self.assertRaises(BenchError) as caught:
            self.bench.sweep([1.0], ["inverse"])
        self.assertEqual(caught.exception.code, "no_model")
        self.assertEqual(caught.exception.rows, [])  # type: ignore[attr-defined]
        with self.assertRaises(FileNotFoundError):
            self.bench.model_load(os.path.join(str(self.daemon.dir), "missing.json"))
        self.assertEqual(self.bench.status()["state"], "idle")  # nothing changed

    def test_track_waits_with_progress_and_its_log_reads_back(self) -> None:
        seen: List[Tuple[float, str]] = []
        result = self.bench.track(
            "triangle",
            compensator="none",
            frequency_hz=2.0,
            periods=4,
            precondition_s=0.2,
            wait=True,
            progress=lambda f, what: seen.append((f, what)),
        )
        self.assertIsInstance(result, RunResult)
        self.assertTrue(result.completed, result)
        self.assertIs(result.check(), result)
        self.assertGreaterEqual(len(seen), 2)
        self.assertTrue(all(0.0 <= f <= 1.0 and what == "track" for f, what in seen), seen)
        self.assertEqual([f for f, _ in seen], sorted(f for f, _ in seen))

        log = read_run(result["log"])
        self.assertEqual(len(log), result["samples"])
        self.assertEqual(log.names, log.header["columns"])
        self.assertEqual(log.header["run"]["kind"], "track")
        self.assertEqual(log.header["run_id"], result["run_id"])
        self.assertEqual(log.units["y"], "um")
        self.assertEqual(log["index"][:3], [0.0, 1.0, 2.0])
        precondition = log.header["run"]["precondition_samples"]
        self.assertEqual(precondition, 2000)
        # The precondition sweep follows no reference: its rows carry the open-loop flag and the
        # model's output as yr; no cell is NaN.
        open_loop = log.header["flags"]["open_loop"]
        flagged = [int(f) & open_loop != 0 for f in log["flags"]]
        self.assertEqual(flagged, [k < precondition for k in range(len(log))])
        self.assertEqual(log["yr"][:precondition], log["y_model"][:precondition])
        self.assertFalse(any(math.isnan(v) for name in log.names for v in log[name]))
        rms, peak = rms_and_max(log, log.header["run"]["metrics_from"])
        self.assertAlmostEqual(rms, result["rms_error_um"], places=9)
        self.assertAlmostEqual(peak, result["max_error_um"], places=9)
        last = self.bench.status()["last_result"]
        self.assertEqual(last["run_id"], result["run_id"])
        listed = self.bench.runs()
        self.assertEqual(listed[0]["run_id"], result["run_id"])
        self.assertEqual(listed[0]["kind"], "track")
        self.assertAlmostEqual(listed[0]["rms_error_percent"], result["rms_error_percent"])
        self.assertEqual(self.bench.run_get(result["run_id"])["samples"], result["samples"])

    def test_track_learns_over_trials_and_reports_each(self) -> None:
        seen: List[str] = []
        result = self.bench.track(
            "sine",
            compensator="none",
            frequency_hz=20.0,
            learn=4,
            precondition_s=0.2,
            wait=True,
            progress=lambda f, what: seen.append(what),
        )
        self.assertTrue(result.completed, result)
        trials = result["learning"]["trials"]
        # The compensator's drive, the same again (what differs is the bench's floor), four learned.
        self.assertEqual([t["trial"] for t in trials], [0, 1, 2, 3, 4, 5])
        self.assertEqual(trials[0]["drive"], "compensator")
        self.assertEqual(trials[1]["drive"], "repeat")
        self.assertGreater(result["learning"]["floor"]["rms_error_percent"], 0.0)
        rms = [t["rms_error_percent"] for t in trials]
        self.assertLess(rms[-1], 0.5 * rms[0], rms)
        self.assertEqual(result["rms_error_percent"], rms[-1])
        self.assertTrue(os.path.exists(result["learning"]["drive_file"]), result["learning"])
        self.assertTrue(any(what.startswith("learning: trial 5 of 5") for what in seen), seen)
        # The learned drive replays by its name, and only for its own reference.
        replay = self.bench.track(
            "sine",
            compensator="none",
            frequency_hz=20.0,
            learned=result["learning"]["drive"],
            precondition_s=0.2,
            wait=True,
        )
        self.assertTrue(replay.completed, replay)
        self.assertEqual(replay["learning"]["trials"][0]["drive"], "saved")
        self.assertLess(replay["rms_error_percent"], 1.5 * rms[-1], replay["learning"])
        with self.assertRaises(BenchError) as refused:
            self.bench.track(
                "triangle", frequency_hz=20.0, learned=result["learning"]["drive"]
            )
        self.assertEqual(refused.exception.code, "bad_params")
        self.assertIn("was learned for", str(refused.exception))

    def test_track_learns_an_uploaded_trajectory_pass_by_pass(self) -> None:
        # Four lines of a raster (a triangle between 10 and 30 um at 5 Hz) at 1 kHz.
        line = [10.0 + 20.0 * (1.0 - abs(1.0 - 2.0 * ((5.0 * k / 1000.0) % 1.0))) for k in range(801)]
        result = self.bench.track(
            line, rate_hz=1000.0, compensator="none", learn=3, precondition_s=0.2, wait=True
        )
        self.assertTrue(result.completed, result)
        learning = result["learning"]
        self.assertEqual(learning["reference"], "upload")
        rms = [t["rms_error_percent"] for t in learning["trials"]]
        self.assertEqual(len(rms), 5, learning)
        self.assertLess(rms[-1], 0.5 * rms[0], rms)
        self.assertGreater(learning["scored_from"], 0)
        self.assertTrue(os.path.exists(learning["drive_file"]), learning)
        # Its drive replays for the same trajectory only.
        replay = self.bench.track(
            line, rate_hz=1000.0, compensator="none", learned=learning["drive"],
            precondition_s=0.2, wait=True,
        )
        self.assertTrue(replay.completed, replay)
        self.assertEqual(replay["learning"]["trials"][0]["drive"], "saved")
        with self.assertRaises(BenchError) as refused:
            self.bench.track(
                [v * 0.9 for v in line], rate_hz=1000.0, learned=learning["drive"]
            )
        self.assertEqual(refused.exception.code, "bad_params")
        # Deleted from the model folder, its CSV too.
        name = learning["drive"] + ".json"
        deleted = self.bench.model_delete(name)["deleted"]
        self.assertEqual(deleted, [name, learning["drive"] + ".csv"])
        self.assertFalse(os.path.exists(learning["drive_file"]))
        self.assertNotIn(name, [m["name"] for m in self.bench.model_list()["models"]])

    def test_a_run_followed_from_another_connection(self) -> None:
        started = self.bench.track(
            compensator="none", frequency_hz=5.0, periods=5, precondition_s=0.1
        )
        self.assertEqual(set(started) >= {"run_id", "log", "duration_s", "samples"}, True)
        self.assertAlmostEqual(started["duration_s"], 1.1)
        with self.daemon.bench() as other:
            running = other.status()
            result = other.wait(started["run_id"], timeout=30)
        self.assertEqual(running["run"]["run_id"], started["run_id"])
        self.assertEqual(result["end"], "completed")
        # Its starter sees the same result, from the event it kept.
        self.assertEqual(
            self.bench.wait(started["run_id"], timeout=30)["run_id"], started["run_id"]
        )

    def test_stop_abort_and_reset(self) -> None:
        started = self.bench.track(compensator="none", frequency_hz=1.0, periods=100)
        with self.assertRaises(BenchError) as caught:
            self.bench.identify()
        self.assertEqual(caught.exception.code, "busy")
        self.assertEqual(self.bench.stop(), {"stopping": True})
        stopped = self.bench.wait(started["run_id"], timeout=30)
        self.assertEqual(stopped["end"], "stopped")
        self.assertFalse(stopped.completed)
        with self.assertRaises(RunEndedError) as ended:
            stopped.check()
        self.assertEqual(ended.exception.code, "stopped")

        started = self.bench.track(compensator="none", frequency_hz=1.0, periods=100)
        aborted = self.bench.abort()
        self.assertTrue(aborted["aborted"])
        self.assertIsInstance(aborted["output_v"], float)
        result = self.bench.wait(started["run_id"], timeout=30)
        self.assertEqual(result["end"], "aborted")
        self.assertEqual(result["output_v_after"], aborted["output_v"])

        with self.assertRaises(BenchError) as caught:
            self.bench.stop()
        self.assertEqual(caught.exception.code, "no_run")
        self.assertEqual(self.bench.reset(), {"was_fault": False, "state": "idle"})

    def test_track_an_uploaded_reference_without_a_model(self) -> None:
        _support.skip_unless_uploads(self.bench)
        reference = ramps([(0.0, 10.0), (0.25, 30.0), (0.3, 30.0), (0.55, 10.0)], RATE_HZ)
        result = self.bench.track(
            reference, rate_hz=RATE_HZ, compensator="none", precondition_s=0.1, wait=True
        )
        self.assertTrue(result.completed, result)
        log = read_run(result["log"])
        self.assertEqual(log.header["run"]["kind"], "track")
        with self.assertRaises(BenchError) as caught:
            self.bench.track([10.0, 20.0, 1000.0, 10.0], rate_hz=100.0, compensator="none")
        e = caught.exception
        self.assertEqual((e.code, e.details.get("sample")), ("out_of_range", 2), e)
        self.assertIn("sample 2", e.message)
        # From a file: the error names its line.
        path = os.path.join(str(self.daemon.dir), "ref.csv")
        with open(path, "w", encoding="utf-8") as f:
            f.write("# yr in um\nt,yr\n0,10\n0.01,20\n0.02,46\n0.03,10\n")
        with self.assertRaises(BenchError) as caught:
            self.bench.track(reference_file=path, compensator="none")
        e = caught.exception
        self.assertEqual((e.code, e.details["line"], e.details["file"]), ("out_of_range", 5, path))
        self.assertIn(f"{path}:5", str(e))
        self.assertIn("of ref.csv", e.message)  # the daemon names the file it was told

    def test_excite_records_an_uploaded_drive(self) -> None:
        _support.skip_unless_excite(self.bench)
        times = [0.0, 0.2, 0.25, 0.45, 0.5]
        drive = [0.0, 150.0, 150.0, 0.0, 0.0]
        seen: List[Tuple[float, str]] = []
        result = self.bench.excite(
            drive, t=times, wait=True, progress=lambda f, what: seen.append((f, what))
        )
        self.assertTrue(result.completed, result)
        self.assertIn((1.0, "upload"), seen)
        log = read_run(result["log"])
        self.assertEqual(log.header["run"]["kind"], "excite")
        self.assertGreater(max(log["u"]), 149.0)
        with self.assertRaises(BenchError) as caught:
            # 150 V in one tick at 10 kHz: 1.5e6 V/s, beyond limits.slew_v_per_s (1e6).
            self.bench.excite([0.0, 0.0, 150.0, 150.0], rate_hz=RATE_HZ)
        e = caught.exception
        # The sample the drive jumps to.
        self.assertEqual((e.code, e.details.get("sample")), ("slew_limit", 2), e)


class WithModelTest(_support.DaemonTestCase):
    identified: RunResult
    progress: List[Tuple[float, str]]

    @classmethod
    def setUpClass(cls) -> None:
        cls.daemon = _support.Daemon("hbpy-b", clock="simulated")
        cls.progress = []
        try:
            with cls.daemon.bench() as bench:
                cls.identified = bench.identify(
                    wait=True, timeout=300, progress=lambda f, what: cls.progress.append((f, what))
                )
        except BaseException:
            cls.daemon.stop()
            raise

    def test_identify_reports_progress_and_adopts_its_model(self) -> None:
        r = self.identified
        self.assertTrue(r.completed, json.dumps(r)[:2000])
        self.assertEqual(r["kind"], "identify")
        # The default family, or the Preisach plane its extension swapped in for the loop's shape.
        self.assertIn(r["model"]["type"], ("mpi", "preisach"), json.dumps(r["model"])[:2000])
        self.assertEqual(r["verification"]["end"], "completed")
        # Virtual time: every sample logged, no lateness.
        self.assertEqual((r["clock"], r.clock), ("simulated", "simulated"))
        self.assertEqual(r["verification"]["clock"], "simulated")
        self.assertEqual((r["dropped"], r["overruns"]), (0, 0))
        self.assertEqual(self.bench.status()["loop"]["clock"], "simulated")
        labels = {what for _, what in self.progress}
        self.assertIn("identify", labels)
        self.assertTrue(any(w.startswith("fitting: ") for w in labels), labels)
        self.assertTrue(any(w.startswith("verify") for w in labels), labels)
        self.assertTrue(all(0.0 <= f <= 1.0 for f, _ in self.progress))
        status = self.bench.status()
        self.assertEqual(status["model"]["path"], r["model"]["path"])
        self.assertEqual(read_run(r["log"], columns=["u", "y"]).names, ["u", "y"])

    def test_sweep_two_frequencies_with_and_without_the_inverse(self) -> None:
        seen: List[Tuple[float, str]] = []
        rows = self.bench.sweep(
            [5.0, 10.0],
            ["none", "inverse"],
            periods=2,
            min_duration_s=0.0,
            precondition_s=0.2,
            progress=lambda f, what: seen.append((f, what)),
        )
        self.assertIsInstance(rows, SweepResult)
        self.assertTrue(rows.completed, rows)
        self.assertEqual(
            [(r["compensator"], r["frequency_hz"]) for r in rows],
            [("none", 5.0), ("none", 10.0), ("inverse", 5.0), ("inverse", 10.0)],
        )
        for r in rows:
            self.assertEqual(r["end"], "completed")
            self.assertGreater(r["max_error_percent"], r["rms_error_percent"])
            self.assertLess(r["min_um"], r["max_um"])
        for f in (5.0, 10.0):
            none, inverse = rows.row(f, "none"), rows.row(f, "inverse")
            self.assertLess(inverse["rms_error_percent"], none["rms_error_percent"] / 3)
        self.assertEqual(seen[-1], (1.0, "inverse 10 Hz (4/4)"))
        self.assertEqual([f for f, _ in seen], sorted(f for f, _ in seen))
        table = rows.table()
        self.assertIn("inverse", table)
        self.assertIn(f"{rows[0]['rms_error_percent']:.3f}", table)

    def test_sweep_with_a_learned_column(self) -> None:
        rows = self.bench.sweep(
            [20.0], ["inverse"], periods=2, min_duration_s=0.0, precondition_s=0.2, learn=3
        )
        self.assertTrue(rows.completed, rows)
        learned, inverse = rows.row(20.0, "learned"), rows.row(20.0, "inverse")
        self.assertEqual(learned["learn_trials"], 3)
        self.assertEqual(len(learned["learning"]["trials_rms_percent"]), 5)
        self.assertLess(learned["rms_error_percent"], inverse["rms_error_percent"])
        self.assertIn("learned", rows.table())

    def test_model_get_and_load_round_trip(self) -> None:
        active = self.bench.model_get()
        self.assertEqual(active["path"], self.identified["model"]["path"])
        document = active["model"]
        self.assertEqual(document["schema"], "hystbench.model/1")
        identified_name = os.path.basename(active["path"])

        loaded = self.bench.model_load(document, name="roundtrip")
        self.assertEqual(loaded["name"], "roundtrip.json")
        self.assertTrue(loaded["invertible"])
        self.assertEqual(self.bench.model_get()["model"], document)

        path = os.path.join(str(self.daemon.dir), "copy-of-model.json")
        with open(path, "w", encoding="utf-8") as f:
            json.dump(document, f, indent=2)
        loaded = self.bench.model_load(path)
        self.assertEqual(loaded["name"], "copy-of-model.json")
        self.assertEqual(self.bench.model_get()["model"], document)

        listed = {m["name"]: m for m in self.bench.model_list()["models"]}
        self.assertTrue(listed["copy-of-model.json"]["active"])
        self.assertEqual(set(listed), {identified_name, "roundtrip.json", "copy-of-model.json"})
        loaded = self.bench.model_load(stored=identified_name)
        self.assertEqual(loaded["name"], identified_name)
        self.assertEqual(self.bench.model_get()["path"], active["path"])
        # The whole reply of model_get() is accepted as well.
        self.assertEqual(self.bench.model_load(active, name="again")["type"], document["type"])
        self.bench.model_load(stored=identified_name)

    def test_track_an_uploaded_reference_through_the_inverse(self) -> None:
        _support.skip_unless_uploads(self.bench)
        points = [(0.0, 8.0), (0.2, 32.0), (0.25, 32.0), (0.45, 8.0), (0.5, 8.0)]
        result = self.bench.track(
            ramps(points, 2000.0),
            rate_hz=2000.0,
            compensator="inverse",
            precondition_s=0.2,
            wait=True,
        )
        self.assertTrue(result.completed, result)
        log = read_run(result["log"], columns=["yr", "y"])
        settled = [abs(y - yr) for y, yr in zip(log["y"], log["yr"]) if not math.isnan(yr)]
        self.assertLess(max(settled[len(settled) // 4 :]), 2.0)  # µm, of a 24 µm stroke


if __name__ == "__main__":
    unittest.main()


class StageTest(_support.DaemonTestCase):
    """A stage of two axes (the loopback's ``[driver.loopback.stage]``, axes x and y), without a
    model: each axis's trajectory uploaded, its result per axis."""

    @classmethod
    def setUpClass(cls) -> None:
        cls.daemon = _support.Daemon(
            "hbpy-xy", _support.SHORT_IDENTIFY + "\n[driver.loopback.stage]\n", clock="simulated"
        )

    def test_each_axis_tracks_its_own_trajectory_and_the_coupling_is_named(self) -> None:
        self.assertEqual(sorted(self.bench.status()["axes"]), ["x", "y"])
        rate = 1000.0
        x = [22.0 + 10.0 * math.sin(2.0 * math.pi * 2.0 * k / rate) for k in range(1001)]
        y = [15.0] * len(x)
        result = self.bench.track_axes(
            {"x": x, "y": y}, rate_hz=rate, compensator="none", precondition_s=0.1, wait=True
        )
        self.assertTrue(result.completed, result)
        for axis in ("x", "y"):
            self.assertTrue(math.isfinite(result["axes"][axis]["rms_error_percent"]), result)
        # x moved and y was held: x's motion shows on y.
        self.assertGreater(abs(result["coupling_error"]["y"]["gain_from"]["x"]), 0.02, result)
        log = read_run(result["log"])
        self.assertIn("y_y", log.columns)
        # From a file with a column per axis; one without y's is refused naming it.
        path = os.path.join(str(self.daemon.dir), "scan.csv")
        with open(path, "w", encoding="utf-8") as f:
            f.write("t,x,y\n" + "".join(f"{k / rate},{x[k]},{y[k]}\n" for k in range(len(x))))
        result = self.bench.track_axes(reference_file=path, compensator="none", wait=True)
        self.assertTrue(result.completed, result)
        with open(path, "w", encoding="utf-8") as f:
            f.write("t,x\n0,10\n0.5,20\n")
        with self.assertRaises(ValueError) as caught:
            self.bench.track_axes(reference_file=path, compensator="none")
        self.assertIn("y", str(caught.exception))
        with self.assertRaises(ValueError) as caught:
            self.bench.track_axes({"x": x}, rate_hz=rate)
        self.assertIn("no reference for axis 'y'", str(caught.exception))
        # The decoupling's kind reaches the daemon, which names what it takes.
        with self.assertRaises(BenchError) as refused:
            self.bench.track_axes({"x": x, "y": y}, rate_hz=rate, decoupling="full")
        self.assertIn("decoupling: 'static' (the default", str(refused.exception))

    def test_a_stages_model_files_go_by_the_axis_each_names(self) -> None:
        with self.assertRaises(ValueError) as caught:
            self.bench.model_load([{"schema": "hystbench.model/1"}])
        self.assertIn("not one axis's model of a stage identify", str(caught.exception))
        # Sent keyed by its axis; the daemon checks the document before it keeps anything.
        with self.assertRaises(BenchError) as refused:
            self.bench.model_load([{"identification": {"stage": {}, "stage_axis": "x"}}])
        self.assertEqual(refused.exception.code, "bad_model")
        self.assertIn("models.x", str(refused.exception))

    def test_each_axis_plays_its_own_drive_open_loop(self) -> None:
        rate = 1000.0
        x = [75.0 + 40.0 * math.sin(2.0 * math.pi * 3.0 * k / rate) for k in range(1001)]
        y = [40.0] * 600  # shorter: y holds its last drive while x plays on
        result = self.bench.excite_axes({"x": x, "y": y}, rate_hz=rate, wait=True)
        self.assertTrue(result.completed, result)
        log = read_run(result["log"])
        self.assertEqual(log.header["run"]["kind"], "excite")
        for column in ("u_x", "y_x", "u_y", "y_y"):
            self.assertIn(column, log.columns)
            self.assertTrue(all(math.isfinite(v) for v in log[column]), column)
        # Each axis played its own drive: x swept 80 V, y held 40 V from its ramp's end on.
        self.assertGreater(max(log["u_x"]) - min(log["u_x"]), 70.0)
        self.assertAlmostEqual(log["u_y"][-1], 40.0, places=9)
        self.assertLess(max(log["u_y"][-300:]) - min(log["u_y"][-300:]), 1e-9)
        with self.assertRaises(ValueError) as caught:
            self.bench.excite_axes({"x": x}, rate_hz=rate)
        self.assertIn("no drive for axis 'y'", str(caught.exception))
        # A drive beyond the output range is refused naming its axis.
        with self.assertRaises(BenchError) as refused:
            self.bench.excite_axes({"x": x, "y": [200.0] * 10}, rate_hz=rate)
        self.assertIn("axis y's drive", str(refused.exception))

"""The client's side of the protocol against a scripted fake daemon (no hystbenchd needed):
replies and errors, events arriving between replies, uploads in chunks under the line limit,
cancelling an upload a run did not take, and the files a run's samples are read from."""

from __future__ import annotations

import json
import os
import shutil
import socket
import tempfile
import threading
import unittest
from unittest import mock
from typing import Any, Callable, Dict, List, Optional

import _support  # noqa: F401  (puts this tree's package on sys.path)
from hystbench import (
    MAX_LINE_BYTES,
    Bench,
    BenchConnectionError,
    BenchError,
    RunEndedError,
    RunResult,
)

Handler = Callable[[str, Dict[str, Any], Any], List[Dict[str, Any]]]


def ok(rid: Any, result: Any) -> Dict[str, Any]:
    return {"id": rid, "ok": True, "result": result}


def err(rid: Any, code: str, message: str, **extra: Any) -> Dict[str, Any]:
    return {"id": rid, "ok": False, "error": {"code": code, "message": message, **extra}}


class FakeDaemon:
    """A Unix socket that greets like hystbenchd and answers each request with ``handler``."""

    def __init__(self, handler: Handler, greeting: Optional[Dict[str, Any]] = None) -> None:
        self.handler = handler
        self.greeting = (
            greeting
            if greeting is not None
            else {
                "hello": "hystbenchd",
                "version": "fake",
                "protocol": 1,
            }
        )
        self.dir = tempfile.mkdtemp(prefix="hbfake-")
        self.path = os.path.join(self.dir, "f.sock")
        self.requests: List[Dict[str, Any]] = []
        self.line_bytes: List[int] = []
        self.listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.listener.bind(self.path)
        self.listener.listen(4)
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.listener.accept()
            except OSError:
                return
            threading.Thread(target=self._talk_and_close, args=(conn,), daemon=True).start()

    def _talk_and_close(self, conn: socket.socket) -> None:
        with conn:
            try:
                self._talk(conn)
            except OSError:
                pass

    def _talk(self, conn: socket.socket) -> None:
        conn.sendall((json.dumps(self.greeting) + "\n").encode())
        buffer = b""
        while True:
            try:
                chunk = conn.recv(1 << 16)
            except OSError:
                return
            if not chunk:
                return
            buffer += chunk
            while b"\n" in buffer:
                line, buffer = buffer.split(b"\n", 1)
                self.line_bytes.append(len(line))
                request = json.loads(line)
                self.requests.append(request)
                out = self.handler(request["cmd"], request.get("params", {}), request.get("id"))
                if out is None:  # close the connection
                    return
                conn.sendall(b"".join((json.dumps(m) + "\n").encode() for m in out))

    def commands(self) -> List[str]:
        return [r["cmd"] for r in self.requests]

    def close(self) -> None:
        self.listener.close()
        shutil.rmtree(self.dir, ignore_errors=True)


class UploadingDaemon:
    """A handler that keeps uploads as hystbenchd's spec says, and starts runs that finish at
    once (events after the start reply)."""

    def __init__(self, max_chunk: int = 2000) -> None:
        self.max_chunk = max_chunk
        self.uploads: Dict[str, Dict[str, Any]] = {}
        self.refuse_run: Optional[Dict[str, Any]] = None
        self.counter = 0

    def __call__(self, cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
        if cmd == "upload.begin":
            self.counter += 1
            name = f"upload-{self.counter}"
            self.uploads[name] = {
                "kind": p["kind"],
                "samples": p["samples"],
                "rate_hz": p.get("rate_hz"),
                "values": [],
                "t": [],
            }
            return [
                ok(
                    rid,
                    {
                        "upload": name,
                        "max_chunk_samples": self.max_chunk,
                        "max_samples": 10_000_000,
                    },
                )
            ]
        if cmd == "upload.chunk":
            u = self.uploads[p["upload"]]
            if p["offset"] != len(u["values"]):
                return [err(rid, "bad_params", "offset")]
            if len(p["values"]) > self.max_chunk:
                return [err(rid, "upload_too_large", "chunk")]
            if (u["rate_hz"] is None) != ("t" in p):
                return [err(rid, "bad_params", "t")]
            u["values"] += p["values"]
            u["t"] += p.get("t", [])
            return [ok(rid, {"received": len(u["values"]), "samples": u["samples"]})]
        if cmd == "upload.cancel":
            self.uploads.pop(p["upload"], None)
            return [ok(rid, {"cancelled": p["upload"]})]
        if cmd in ("track", "excite"):
            if self.refuse_run is not None:
                return [err(rid, **self.refuse_run)]
            key = "reference_upload" if cmd == "track" else "drive_upload"
            self.uploads.pop(p[key])
            run = f"run-{cmd}"
            return [
                ok(rid, {"run_id": run, "log": f"/logs/{run}.csv"}),
                {"event": "run.progress", "run_id": run, "kind": cmd, "fraction": 0.5},
                {
                    "event": "run.finished",
                    "result": {"run_id": run, "kind": cmd, "end": "completed"},
                },
            ]
        return [err(rid, "unknown_command", cmd)]


class ProtocolTest(unittest.TestCase):
    def serve(self, handler: Handler, **kw: Any) -> FakeDaemon:
        fake = FakeDaemon(handler, **kw)
        self.addCleanup(fake.close)
        return fake

    def connect(self, fake: FakeDaemon) -> Bench:
        bench = Bench(fake.path, timeout=5.0)
        self.addCleanup(bench.close)
        return bench

    def test_replies_errors_and_their_details(self) -> None:
        def handler(cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
            if cmd == "status":
                return [ok(rid, {"state": "idle"})]
            return [err(rid, "out_of_range", "row 17: 99 um is beyond the range", row=17)]

        fake = self.serve(handler)
        bench = self.connect(fake)
        self.assertEqual(bench.greeting["hello"], "hystbenchd")
        self.assertEqual(bench.protocol, 1)
        self.assertEqual(bench.status(), {"state": "idle"})
        with self.assertRaises(BenchError) as caught:
            bench.request("track", {"reference_upload": "x"})
        e = caught.exception
        self.assertEqual((e.code, e.details, e.command), ("out_of_range", {"row": 17}, "track"))
        self.assertIn("row 17", str(e))
        self.assertIn("[out_of_range]", str(e))
        ids = [r["id"] for r in fake.requests]
        self.assertEqual(ids, sorted(set(ids)))

    def test_nan_is_refused_before_anything_is_sent(self) -> None:
        fake = self.serve(lambda cmd, p, rid: [ok(rid, {})])
        bench = self.connect(fake)
        with self.assertRaisesRegex(ValueError, "NaN or infinity"):
            bench.track(frequency_hz=float("nan"))
        with self.assertRaisesRegex(ValueError, r"values\[1\]"):
            bench.upload("reference", [1.0, float("inf")], rate_hz=10.0)
        self.assertEqual(fake.requests, [])

    def test_wait_follows_events_that_came_with_other_replies(self) -> None:
        def handler(cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
            if cmd == "identify":
                return [
                    {"event": "run.progress", "run_id": "other", "fraction": 0.9},
                    ok(rid, {"run_id": "r1", "log": "/x.csv"}),
                    {"event": "run.progress", "run_id": "r1", "kind": "identify", "fraction": 0.5},
                ]
            if cmd == "status":
                return [
                    ok(rid, {"state": "running", "run": {"run_id": "r1"}, "last_result": None}),
                    {"event": "fit.progress", "run_id": "r1", "fraction": 0.25, "stage": "mpi"},
                    {
                        "event": "run.progress",
                        "run_id": "r1",
                        "kind": "identify",
                        "fraction": 0.1,
                        "stage": "verify mpi",
                    },
                    {
                        "event": "run.finished",
                        "result": {"run_id": "r1", "end": "aborted", "reason": "abort requested"},
                    },
                ]
            return [err(rid, "unknown_command", cmd)]

        fake = self.serve(handler)
        bench = self.connect(fake)
        started = bench.identify(model="mpi")
        self.assertEqual(started, {"run_id": "r1", "log": "/x.csv"})
        # Another connection waits for the same run: it asks for the status first.
        other = self.connect(fake)
        seen: List[Any] = []
        result = other.wait("r1", progress=lambda f, w: seen.append((f, w)), timeout=5)
        self.assertIsInstance(result, RunResult)
        self.assertEqual(seen, [(0.25, "fitting: mpi"), (0.1, "verify mpi")])
        self.assertEqual(result.end, "aborted")
        self.assertFalse(result.completed)
        with self.assertRaises(RunEndedError) as caught:
            result.check()
        self.assertEqual(caught.exception.code, "aborted")
        self.assertIs(caught.exception.result, result)

    def test_a_sweep_holds_its_bar_while_a_run_is_prepared(self) -> None:
        # A track run of a rate-dependent model plans its feedforward before it starts: the
        # sweep's bar names the stage and moves only with the run itself.
        def handler(cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
            if cmd != "track":
                return [err(rid, "unknown_command", cmd)]
            run_id = f"r{p['frequency_hz']:g}"
            progress = {"event": "run.progress", "run_id": run_id, "kind": "track"}
            return [
                ok(rid, {"run_id": run_id, "feedforward": {"planned": {"planning": True}}}),
                dict(progress, fraction=0.5, stage="planning the feedforward"),
                dict(progress, fraction=1.0, stage="planning the feedforward"),
                dict(progress, fraction=0.5),
                {"event": "run.finished", "result": {"run_id": run_id, "end": "completed"}},
            ]

        bench = self.connect(self.serve(handler))
        seen: List[Any] = []
        rows = bench.sweep([5.0, 10.0], ["inverse"], progress=lambda f, w: seen.append((f, w)))
        self.assertTrue(rows.completed)
        self.assertEqual(
            seen,
            [
                (0.0, "inverse 5 Hz (1/2): planning the feedforward"),
                (0.0, "inverse 5 Hz (1/2): planning the feedforward"),
                (0.25, "inverse 5 Hz (1/2)"),
                (0.5, "inverse 5 Hz (1/2)"),  # the run finished
                (0.5, "inverse 10 Hz (2/2): planning the feedforward"),
                (0.5, "inverse 10 Hz (2/2): planning the feedforward"),
                (0.75, "inverse 10 Hz (2/2)"),
                (1.0, "inverse 10 Hz (2/2)"),
            ],
        )

    def test_wait_for_a_run_that_already_ended_uses_the_last_result(self) -> None:
        def handler(cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
            return [
                ok(
                    rid,
                    {
                        "state": "idle",
                        "run": None,
                        "last_result": {"run_id": "old", "end": "completed"},
                    },
                )
            ]

        bench = self.connect(self.serve(handler))
        self.assertTrue(bench.wait("old", timeout=1).completed)
        with self.assertRaises(BenchError) as caught:
            bench.wait("unknown", timeout=1)
        self.assertEqual(caught.exception.code, "no_run")

    def test_uploads_with_times_fit_the_line_limit(self) -> None:
        daemon = UploadingDaemon()
        fake = self.serve(daemon)
        bench = self.connect(fake)
        n = 4500
        t = [k / 3.0e3 + 1e-7 * (k % 7) for k in range(n)]
        values = [10.0 + 20.0 * (k % 100) / 99.0 + 1e-9 * k for k in range(n)]
        seen: List[float] = []
        # A limit that 2000 samples with their times exceed, so that the chunks must split.
        limit = 64 * 1024
        with mock.patch("hystbench.client.MAX_LINE_BYTES", limit):
            result = bench.track(
                t=t,
                reference=values,
                compensator="inverse",
                wait=True,
                progress=lambda f, w: seen.append(f),
            )
        self.assertTrue(result.completed)
        begin = fake.requests[0]
        self.assertEqual(begin["cmd"], "upload.begin")
        self.assertEqual(begin["params"], {"kind": "reference", "samples": n})
        chunks = [r for r in fake.requests if r["cmd"] == "upload.chunk"]
        offsets = [c["params"]["offset"] for c in chunks]
        sizes = [len(c["params"]["values"]) for c in chunks]
        self.assertLess(sizes[0], 2000)  # 2000 values with their times exceed the limit
        self.assertLessEqual(max(fake.line_bytes), limit)
        self.assertGreater(MAX_LINE_BYTES, 80_000)  # an identified model file fits in one line
        self.assertEqual(offsets, [sum(sizes[:i]) for i in range(len(sizes))])
        self.assertEqual(sum(sizes), n)
        self.assertEqual([v for c in chunks for v in c["params"]["values"]], values)
        self.assertEqual([v for c in chunks for v in c["params"]["t"]], t)
        track = [r for r in fake.requests if r["cmd"] == "track"][0]
        self.assertEqual(
            track["params"], {"compensator": "inverse", "reference_upload": "upload-1"}
        )
        self.assertAlmostEqual(seen[len(chunks) - 1], 1.0)  # upload progress, then the run's
        self.assertEqual(bench.wait("run-track", timeout=1), result)  # again: kept

    def test_uniform_uploads_send_values_only(self) -> None:
        daemon = UploadingDaemon(max_chunk=1000)
        fake = self.serve(daemon)
        bench = self.connect(fake)
        upload = bench.upload("drive", [float(k % 150) for k in range(2500)], rate_hz=10000)
        chunks = [r["params"] for r in fake.requests if r["cmd"] == "upload.chunk"]
        self.assertEqual([len(c["values"]) for c in chunks], [1000, 1000, 500])
        self.assertTrue(all("t" not in c for c in chunks))
        self.assertEqual(fake.requests[0]["params"]["rate_hz"], 10000.0)
        self.assertEqual(len(daemon.uploads[upload]["values"]), 2500)

    def test_a_refused_run_cancels_its_upload(self) -> None:
        daemon = UploadingDaemon()
        daemon.refuse_run = {"code": "slew_limit", "message": "row 3: too fast", "row": 3}
        fake = self.serve(daemon)
        bench = self.connect(fake)
        with self.assertRaises(BenchError) as caught:
            bench.excite([0.0, 1.0, 150.0, 0.0], rate_hz=10000.0, precondition_s=0.5)
        self.assertEqual(
            (caught.exception.code, caught.exception.details), ("slew_limit", {"row": 3})
        )
        self.assertEqual(fake.commands()[-2:], ["excite", "upload.cancel"])
        self.assertEqual(
            fake.requests[-2]["params"], {"precondition_s": 0.5, "drive_upload": "upload-1"}
        )
        self.assertEqual(daemon.uploads, {})

    def test_a_refused_chunk_cancels_the_upload(self) -> None:
        def handler(cmd: str, p: Dict[str, Any], rid: Any) -> List[Dict[str, Any]]:
            if cmd == "upload.begin":
                return [ok(rid, {"upload": "u", "max_chunk_samples": 2, "max_samples": 10})]
            if cmd == "upload.chunk" and p["offset"] >= 2:
                return [err(rid, "bad_params", "t[0] (sample 2): times must increase", sample=2)]
            return [ok(rid, {"received": p.get("offset", 0) + 2, "samples": 4})]

        fake = self.serve(handler)
        bench = self.connect(fake)
        with self.assertRaises(BenchError) as caught:
            bench.upload("reference", [1, 2, 3, 4], t=[0, 1, 1, 2])
        self.assertEqual(caught.exception.details, {"sample": 2})
        self.assertEqual(
            fake.commands(), ["upload.begin", "upload.chunk", "upload.chunk", "upload.cancel"]
        )

    def test_reference_and_input_files(self) -> None:
        daemon = UploadingDaemon()
        fake = self.serve(daemon)
        bench = self.connect(fake)
        folder = tempfile.mkdtemp(prefix="hbfiles-")
        self.addCleanup(shutil.rmtree, folder, True)
        ref = os.path.join(folder, "ref.csv")
        with open(ref, "w") as f:
            f.write("# a raster line\nt,yr,other\n0,5,x\n0.001,6,x\n0.002,7,x\n")
        drive = os.path.join(folder, "drive.dat")
        with open(drive, "w") as f:
            f.write("0.0 10\n0.5 20\n1.0 30\n")
        bench.track(reference_file=ref, wait=True)
        bench.excite(input_file=drive, columns=(None, "2"), rate_hz=2.0, wait=True)
        begins = [r["params"] for r in fake.requests if r["cmd"] == "upload.begin"]
        self.assertEqual(begins[0], {"kind": "reference", "samples": 3, "source": "ref.csv"})
        self.assertEqual(
            begins[1], {"kind": "drive", "samples": 3, "rate_hz": 2.0, "source": "drive.dat"}
        )
        chunks = [r["params"] for r in fake.requests if r["cmd"] == "upload.chunk"]
        self.assertEqual(
            chunks[0],
            {
                "upload": "upload-1",
                "offset": 0,
                "values": [5.0, 6.0, 7.0],
                "t": [0.0, 0.001, 0.002],
            },
        )
        self.assertEqual(
            chunks[1], {"upload": "upload-2", "offset": 0, "values": [10.0, 20.0, 30.0]}
        )
        with self.assertRaisesRegex(ValueError, r"no column 'u' \(columns: t, yr, other\)"):
            bench.excite(input_file=ref)
        with self.assertRaisesRegex(ValueError, "not both"):
            bench.track("sine", reference_file=ref)
        with self.assertRaisesRegex(ValueError, "waveform"):
            bench.track([1.0, 2.0], rate_hz=10.0, frequency_hz=5.0)

    def test_connection_problems_name_the_socket(self) -> None:
        missing = os.path.join(tempfile.gettempdir(), "hystbench-no-such-dir", "s.sock")
        with self.assertRaises(ConnectionError) as caught:
            Bench(missing)
        self.assertIsInstance(caught.exception, BenchConnectionError)
        self.assertIn(missing, str(caught.exception))
        self.assertIn("is hystbenchd running", str(caught.exception))

        quiet = self.serve(lambda cmd, p, rid: [], greeting={"not": "hystbenchd"})
        with self.assertRaisesRegex(BenchConnectionError, "no hystbenchd greeting"):
            Bench(quiet.path, timeout=1.0)

        closing = self.serve(lambda cmd, p, rid: None)
        bench = self.connect(closing)
        with self.assertRaises(BenchConnectionError) as caught:
            bench.status()
        self.assertIn(closing.path, str(caught.exception))
        self.assertIn("closed the connection", str(caught.exception))
        self.assertTrue(bench.closed)

    def test_default_socket_from_the_environment(self) -> None:
        fake = self.serve(lambda cmd, p, rid: [ok(rid, {"state": "idle"})])
        old = os.environ.get("HYSTBENCH_SOCKET")
        os.environ["HYSTBENCH_SOCKET"] = fake.path
        try:
            with Bench() as bench:
                self.assertEqual(bench.socket_path, fake.path)
                self.assertEqual(bench.status()["state"], "idle")
            self.assertTrue(bench.closed)
        finally:
            if old is None:
                del os.environ["HYSTBENCH_SOCKET"]
            else:
                os.environ["HYSTBENCH_SOCKET"] = old

    def test_a_missing_reply_times_out(self) -> None:
        bench = self.connect(self.serve(lambda cmd, p, rid: []))
        bench.timeout = 0.2
        with self.assertRaisesRegex(TimeoutError, "no reply to 'status'"):
            bench.status()


if __name__ == "__main__":
    unittest.main()

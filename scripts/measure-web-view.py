#!/usr/bin/python3
"""The loop's execution time with the live view open in a browser, against none (target: exec p99
within 10 % of its value without a browser).

  scripts/measure-web-view.py [--daemon build/bin/hystbenchd] [--cli build/bin/hystbench]
                              [--seconds 20] [--rounds 2] [--loop-cpu N --browser-cpus LIST]

One hystbenchd on config/loopback.toml (wall clock, 10 kHz, SCHED_FIFO where permitted) with the
view on; tracking runs of --seconds each (a 5 Hz sine, compensator none), alternately with no
browser and with headless Chromium showing the page (scope streaming), in the order A B B A per
round so that a drift of the machine weighs on both alike. --loop-cpu pins the loop thread to a
CPU ([loop] cpu) and --browser-cpus runs Chromium on others (taskset), as a bench PC that keeps a
core for the loop would. Each run's own timing (its result's
loop.exec_ns and wake_latency_ns) is read; prints each run and the medians' ratio. Needs
chromium and python3-websocket (as tests/daemon/http/browser_view_test.py, whose helpers it uses).
"""

import argparse
import json
import os
import statistics
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "daemon", "http"))
import browser_view_test as bv  # noqa: E402


def track(args, sock):
    code, out, err = bv.cli(args, sock, "track", "--reference", "sine", "--frequency", "5",
                            "--duration", str(args.seconds), "--compensator", "none", "--wait",
                            "--json", timeout=args.seconds + 60)
    try:
        result = json.loads(out)
    except ValueError:
        raise bv.Failure("track: no JSON (exit %d): %s %s" % (code, out.strip(), err.strip()))
    if result.get("end") != "completed":
        raise bv.Failure("track ended %s: %s" % (result.get("end"), result.get("reason")))
    loop = result["loop"]
    return loop["exec_ns"]["p99"], loop["wake_latency_ns"]["p99"], result.get("overruns", 0)


class StreamReader:
    """Reads the view's stream on a thread of its own until closed; counts the bytes."""

    def __init__(self, url):
        import threading
        import urllib.request
        self.bytes = 0
        self.response = urllib.request.urlopen(url, timeout=30)
        self.thread = threading.Thread(target=self._read, daemon=True)
        self.thread.start()

    def _read(self):
        try:
            while True:
                chunk = self.response.read1(65536)
                if not chunk:
                    return
                self.bytes += len(chunk)
        except (OSError, ValueError, AttributeError):  # closed under the read
            return

    def close(self):
        self.response.close()
        self.thread.join(5)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--daemon", default=os.path.join(ROOT, "build", "bin", "hystbenchd"))
    ap.add_argument("--cli", default=os.path.join(ROOT, "build", "bin", "hystbench"))
    ap.add_argument("--config", default=os.path.join(ROOT, "config", "loopback.toml"))
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--loop-cpu", type=int, default=-1, help="[loop] cpu (default: none)")
    ap.add_argument("--browser-cpus", default="", help="taskset CPU list for Chromium")
    ap.add_argument("--client", choices=("browser", "stream"), default="browser",
                    help="what is attached: the page in Chromium, or only a reader of the stream "
                         "(the view's own cost, without the browser's drawing)")
    args = ap.parse_args()
    chromium = bv.find_chromium()
    if not chromium:
        print("chromium not found (apt install chromium)")
        return 1
    websocket = bv.import_websocket()
    procs = bv.Processes()
    with tempfile.TemporaryDirectory(prefix="hb-measure-view-") as tmp:
        try:
            sock = os.path.join(tmp, "s.sock")
            log = os.path.join(tmp, "hystbenchd.log")
            config = os.path.join(tmp, "hystbenchd.toml")
            with open(args.config) as f:
                text = f.read()
            with open(config, "w") as f:
                f.write(text.replace("[loop]\n", "[loop]\ncpu = %d\n" % args.loop_cpu, 1))
            daemon = procs.start([args.daemon, "--config", config, "--socket", sock,
                                  "--log-dir", os.path.join(tmp, "logs"), "--model-dir",
                                  os.path.join(tmp, "models"), "--http", "127.0.0.1:0"], log)
            base = "http://" + bv.http_address(args, sock, daemon, log)
            figures = {"none": [], "browser": []}
            browser = [chromium] if not args.browser_cpus else \
                ["taskset", "-c", args.browser_cpus, chromium]
            dev = None
            on_page = False
            for _ in range(args.rounds):
                for mode in ("none", "browser", "browser", "none"):
                    if mode == "browser" and args.client == "stream":
                        reader = StreamReader(base + "/api/stream")
                        exec_p99, wake_p99, overruns = track(args, sock)
                        reader.close()
                        figures[mode].append(exec_p99)
                        print("stream   exec p99 %6d ns  wake p99 %7d ns  overruns %d  bytes %d"
                              % (exec_p99, wake_p99, overruns, reader.bytes), flush=True)
                        continue
                    if mode == "browser" and dev is None:
                        dev = bv.launch_browser(procs, browser, tmp, websocket)
                        dev.call("Page.enable")
                    if mode == "browser" and not on_page:
                        dev.call("Page.navigate", url=base + "/")
                        dev.wait_for("!!(window.hystbenchView && hystbenchView.frames > 0)", 20,
                                     "the page's scope")
                        on_page = True
                    if mode == "none" and on_page:
                        dev.call("Page.navigate", url="about:blank")  # the page closes its stream
                        on_page = False
                    exec_p99, wake_p99, overruns = track(args, sock)
                    frames = dev.eval("window.hystbenchView ? hystbenchView.frames : 0") \
                        if dev is not None and mode == "browser" else 0
                    figures[mode].append(exec_p99)
                    print("%-8s exec p99 %6d ns  wake p99 %7d ns  overruns %d  page frames %s"
                          % (mode, exec_p99, wake_p99, overruns, frames), flush=True)
            none = statistics.median(figures["none"])
            browser = statistics.median(figures["browser"])
            print("figure exec_p99_none_ns=%d exec_p99_browser_ns=%d ratio=%.3f"
                  % (none, browser, browser / none))
            return 0
        except bv.Failure as e:
            print("FAIL: %s" % e)
            return 1
        finally:
            procs.stop_all()


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/python3
"""The live view in a real browser: a real hystbenchd on the loopback actuator serving its page to
Debian's headless Chromium, driven over the Chrome DevTools Protocol (docs/reference/web-view.md).

  browser_view_test.py --daemon build/bin/hystbenchd --cli build/bin/hystbench [--out DIR]

Checks: the page paints within 1 s and its stream connects; a track run started with the CLI moves
the scope (frames and the newest seq grow, at least 20 redraws a second while it runs); the
finished run appears in the runs table and its row plots the run; a screenshot (PNG, in --out) is
not blank; an unknown path is a JSON 404; a command that changes the bench is refused (403) without
control; the daemon is still alive at the end. Then a second daemon with `[http] control = true`
and a token file: the page's control panel is refused with a wrong token and starts a track with
the right one, which ends in the list. Prints `figure name=value ...` lines.

Exit 0 pass, 1 fail, 77 skipped (no chromium or no python3-websocket). Standard library plus
python3-websocket only. About 15 s.
"""

import argparse
import base64
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
import zlib

SKIP = 77
FIRST_PAINT_MAX_MS = 1000.0
SCOPE_FPS_MIN = 20.0

class Failure(Exception):
    pass


def check(cond, message):
    if not cond:
        raise Failure(message)


def import_websocket():
    """python3-websocket, from Debian's python3 when this one lacks it (re-executes there)."""
    try:
        import websocket  # noqa: F401  (python3-websocket)
        return websocket
    except ImportError:
        system = "/usr/bin/python3"
        other = os.path.realpath(sys.executable) != os.path.realpath(system)
        if os.path.exists(system) and other and not os.environ.get("HB_BROWSER_TEST_REEXEC"):
            os.environ["HB_BROWSER_TEST_REEXEC"] = "1"
            os.execv(system, [system] + sys.argv)
        print("SKIP: python3-websocket not found (apt install python3-websocket)")
        sys.exit(SKIP)


# ---------------------------------------------------------------------------- processes


class Processes:
    """Every process this test starts, each in its own process group; all ended on exit."""

    def __init__(self):
        self.procs = []

    def start(self, argv, log_path):
        log = open(log_path, "wb")
        p = subprocess.Popen(argv, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                             start_new_session=True)
        log.close()
        self.procs.append(p)
        return p

    def stop(self, p):
        """Ends one of them (SIGTERM, then SIGKILL after 5 s)."""
        if p.poll() is None:
            p.terminate()
            try:
                p.wait(5)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()

    def stop_all(self):
        """SIGTERM to each leader (chromium then ends its own children; the daemon its run), then
        SIGKILL to whatever of its group is left after 5 s."""
        for p in reversed(self.procs):
            if p.poll() is None:
                p.terminate()
        deadline = time.monotonic() + 5
        for p in reversed(self.procs):
            try:
                p.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
            try:
                os.killpg(p.pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
            p.wait()


def cli(args, socket_path, *rest, timeout=15):
    r = subprocess.run([args.cli, "--socket", socket_path] + list(rest), capture_output=True,
                       text=True, timeout=timeout)
    return r.returncode, r.stdout, r.stderr


def cli_json(args, socket_path, *rest):
    code, out, err = cli(args, socket_path, *rest)
    try:
        return json.loads(out)
    except ValueError:
        raise Failure("hystbench %s: no JSON (exit %d): %s %s"
                      % (" ".join(rest), code, out.strip(), err.strip()))


def tail(path, n=20):
    try:
        with open(path, errors="replace") as f:
            return "".join(f.readlines()[-n:])
    except OSError:
        return ""


def http_address(args, socket_path, daemon, log_path, timeout=20):
    deadline = time.monotonic() + timeout
    last = ""
    while time.monotonic() < deadline:
        if daemon.poll() is not None:
            raise Failure("hystbenchd exited (%d) at start:\n%s"
                          % (daemon.returncode, tail(log_path)))
        if os.path.exists(socket_path):
            code, out, err = cli(args, socket_path, "status")
            last = (out + err).strip()[-300:]
            try:
                address = (json.loads(out).get("http") or {}).get("address")
            except ValueError:
                address = None
            if address:
                return address
        time.sleep(0.1)
    raise Failure("no http.address in `hystbench status` within %d s (last: %s)\n%s"
                  % (timeout, last, tail(log_path)))


def http(url, body=None):
    """(status, parsed JSON or None, content type) of a GET, or a POST of body (a dict)."""
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method="POST" if data else "GET",
                                 headers={"Content-Type": "application/json"} if data else {})
    try:
        with urllib.request.urlopen(req, timeout=5) as r:
            status, raw, ctype = r.status, r.read(), r.headers.get("Content-Type", "")
    except urllib.error.HTTPError as e:
        status, raw, ctype = e.code, e.read(), e.headers.get("Content-Type", "")
    try:
        return status, json.loads(raw), ctype
    except ValueError:
        return status, None, ctype


# ---------------------------------------------------------------------------- DevTools


class DevTools:
    """One page target over the Chrome DevTools Protocol: calls by id, events kept aside."""

    def __init__(self, websocket, ws_url):
        self.ws = websocket.create_connection(ws_url, timeout=10, suppress_origin=True)
        self.next_id = 0
        self.exceptions = []
        self.console_errors = []

    def _event(self, msg):
        method = msg.get("method")
        params = msg.get("params", {})
        if method == "Runtime.exceptionThrown":
            d = params.get("exceptionDetails", {})
            self.exceptions.append((d.get("exception") or {}).get("description") or d.get("text"))
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            e = params["entry"]
            self.console_errors.append("%s (%s)" % (e.get("text"), e.get("url", "")))
        elif method == "Runtime.consoleAPICalled" and params.get("type") == "error":
            self.console_errors.append(" ".join(str(a.get("value", a.get("description", "")))
                                                for a in params.get("args", [])))

    def call(self, method, timeout=10, **params):
        self.next_id += 1
        my_id = self.next_id
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        deadline = time.monotonic() + timeout
        while True:
            self.ws.settimeout(max(0.1, deadline - time.monotonic()))
            msg = json.loads(self.ws.recv())
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise Failure("DevTools %s: %s" % (method, msg["error"]))
                return msg.get("result", {})
            if "method" in msg:
                self._event(msg)
            if time.monotonic() > deadline:
                raise Failure("DevTools %s: no reply within %g s" % (method, timeout))

    def eval(self, expression):
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True,
                      awaitPromise=True)
        if "exceptionDetails" in r:
            raise Failure("page: %s threw %s" % (expression, r["exceptionDetails"].get("text")))
        return r.get("result", {}).get("value")

    def view(self):
        """window.hystbenchView with the page's clock (now, ms)."""
        return json.loads(self.eval(
            "JSON.stringify(Object.assign({now: performance.now()}, window.hystbenchView || {}))"))

    def wait_for(self, expression, timeout, what):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.eval(expression):
                return
            time.sleep(0.1)
        raise Failure("page: %s not within %g s (%s)" % (what, timeout, expression))

    def close(self):
        try:
            self.ws.close()
        except Exception:
            pass


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def launch_browser(procs, chromium, tmp, websocket):
    profile = os.path.join(tmp, "chromium")
    os.makedirs(profile)
    command = chromium if isinstance(chromium, list) else [chromium]  # e.g. under taskset
    browser = procs.start(command + ["--headless=new", "--no-sandbox", "--disable-gpu",
                           "--hide-scrollbars", "--no-first-run", "--no-default-browser-check",
                           "--window-size=1280,1600", "--remote-debugging-port=0",
                           "--user-data-dir=" + profile, "about:blank"],
                          os.path.join(tmp, "chromium.log"))
    port_file = os.path.join(profile, "DevToolsActivePort")
    deadline = time.monotonic() + 20
    port = None
    while time.monotonic() < deadline and port is None:
        if browser.poll() is not None:
            raise Failure("chromium exited (%d):\n%s" % (browser.returncode,
                                                         tail(os.path.join(tmp, "chromium.log"))))
        try:
            with open(port_file) as f:
                first = f.readline().strip()
            port = int(first) if first else None
        except (OSError, ValueError):
            pass
        if port is None:
            time.sleep(0.05)
    check(port is not None, "chromium wrote no DevToolsActivePort within 20 s")
    for _ in range(50):
        try:
            with urllib.request.urlopen("http://127.0.0.1:%d/json/list" % port, timeout=5) as r:
                pages = [t for t in json.load(r) if t.get("type") == "page"]
            if pages:
                return DevTools(websocket, pages[0]["webSocketDebuggerUrl"])
        except (OSError, ValueError):
            pass
        time.sleep(0.1)
    raise Failure("chromium has no page target on port %d" % port)


# ---------------------------------------------------------------------------- PNG


def png_stats(data):
    """(width, height, distinct colours, rows unlike the first row) of an 8-bit PNG."""
    check(data[:8] == b"\x89PNG\r\n\x1a\n", "screenshot is not a PNG")
    pos, idat, ihdr = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        chunk = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", chunk)
        elif kind == b"IDAT":
            idat.append(chunk)
        pos += 12 + length
    width, height, depth, ctype, _, _, interlace = ihdr
    check(depth == 8 and ctype in (2, 6) and interlace == 0,
          "screenshot PNG: unexpected format (depth %d, colour type %d)" % (depth, ctype))
    bpp = 4 if ctype == 6 else 3
    raw = zlib.decompress(b"".join(idat))
    stride = width * bpp
    prev = bytearray(stride)
    colours, first, differing = set(), None, 0
    for y in range(height):
        base = y * (stride + 1)
        ftype = raw[base]
        row = bytearray(raw[base + 1:base + 1 + stride])
        if ftype == 1:
            for i in range(bpp, stride):
                row[i] = (row[i] + row[i - bpp]) & 255
        elif ftype == 2:
            row = bytearray((a + b) & 255 for a, b in zip(row, prev))
        elif ftype == 3:
            for i in range(stride):
                left = row[i - bpp] if i >= bpp else 0
                row[i] = (row[i] + ((left + prev[i]) >> 1)) & 255
        elif ftype == 4:
            for i in range(stride):
                a = row[i - bpp] if i >= bpp else 0
                b = prev[i]
                c = prev[i - bpp] if i >= bpp else 0
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[i] = (row[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        if first is None:
            first = bytes(row)
        elif row != first:
            differing += 1
        if y % 4 == 0:
            for x in range(0, stride, bpp * 3):
                colours.add(bytes(row[x:x + 3]))
        prev = row
    return width, height, len(colours), differing


# ---------------------------------------------------------------------------- the test


def run(args, procs, tmp, websocket):
    socket_path = os.path.join(tmp, "s.sock")
    daemon_log = os.path.join(tmp, "hystbenchd.log")
    # The shipped loopback configuration (its range lets a track run without a model), with the
    # test's folders and the view switched on from the command line, as a user would.
    argv = [args.daemon] + (["--config", args.config] if args.config else []) + [
        "--socket", socket_path, "--log-dir", os.path.join(tmp, "logs"),
        "--model-dir", os.path.join(tmp, "models"), "--http", "127.0.0.1:0"] + args.daemon_arg
    daemon = procs.start(argv, daemon_log)
    address = http_address(args, socket_path, daemon, daemon_log)
    base = "http://" + address
    print("hystbenchd: %s" % base)

    dev = launch_browser(procs, args.chromium, tmp, websocket)
    dev.call("Runtime.enable")
    dev.call("Log.enable")
    dev.call("Page.enable")
    dev.call("Page.navigate", url=base + "/")
    dev.wait_for("!!(window.hystbenchView && hystbenchView.connected"
                 " && hystbenchView.firstPaintMs !== null && hystbenchView.frames > 0)",
                 10, "stream connected, first paint and a scope frame")
    v = dev.view()
    first_paint = v["firstPaintMs"]
    print("figure first_paint_ms=%.0f" % first_paint)
    check(first_paint <= FIRST_PAINT_MAX_MS,
          "first paint %.0f ms > %.0f ms" % (first_paint, FIRST_PAINT_MAX_MS))

    reply = cli_json(args, socket_path, "track", "--reference", "sine", "--frequency", "5",
                     "--periods", "20", "--compensator", "none", "--json")
    run_id = reply.get("run_id")
    check(run_id, "track refused: %s" % json.dumps(reply))
    print("track run %s started (%s s)" % (run_id, reply.get("duration_s")))
    time.sleep(0.5)
    a = dev.view()
    time.sleep(2.0)
    b = dev.view()
    dt = (b["now"] - a["now"]) / 1000.0
    fps = (b["frames"] - a["frames"]) / dt
    rate = (b["samples"] - a["samples"]) / dt
    print("figure scope_fps=%.1f scope_samples_per_s=%.0f" % (fps, rate))
    check(b["frames"] > a["frames"],
          "the scope did not redraw during the track (%s -> %s)" % (a, b))
    check(b["lastSeq"] is not None and a["lastSeq"] is not None and b["lastSeq"] > a["lastSeq"],
          "lastSeq did not grow during the track (%s -> %s)" % (a["lastSeq"], b["lastSeq"]))
    check(b["connected"], "stream not connected during the track")
    check(fps >= SCOPE_FPS_MIN, "scope at %.1f fps during the track (< %g)" % (fps, SCOPE_FPS_MIN))

    deadline = time.monotonic() + 30
    while True:
        s = cli_json(args, socket_path, "status", "--json")
        if s.get("run") is None and (s.get("last_result") or {}).get("run_id") == run_id:
            break
        check(time.monotonic() < deadline, "run %s did not finish within 30 s" % run_id)
        time.sleep(0.2)
    end = s["last_result"].get("end")
    print("track run %s ended: %s" % (run_id, end))
    row = "#runs tr[data-run-id=%s]" % json.dumps(run_id)
    dev.wait_for("!!document.querySelector(%s)" % json.dumps(row), 5, "the run's row in #runs")
    shown = dev.view()["runsShown"]
    check(shown >= 1, "runsShown %s after the run finished" % shown)
    dev.eval("document.querySelector(%s).click()" % json.dumps(row))
    dev.wait_for("!!document.querySelector('#run-plot canvas') && document.getElementById("
                 "'run-result').textContent.indexOf(%s) >= 0" % json.dumps(run_id),
                 5, "the run's plot and result after a click on its row")
    time.sleep(0.3)

    shot = dev.call("Page.captureScreenshot", format="png", timeout=20)
    png = base64.b64decode(shot["data"])
    os.makedirs(args.out, exist_ok=True)
    shot_path = os.path.join(args.out, "browser_view.png")
    with open(shot_path, "wb") as f:
        f.write(png)
    width, height, colours, rows = png_stats(png)
    print("screenshot %s: %dx%d, %d colours, %d rows unlike the first"
          % (shot_path, width, height, colours, rows))
    check(colours >= 16 and rows >= height // 4,
          "screenshot looks blank (%d colours, %d of %d rows differ)" % (colours, rows, height))

    status, body, ctype = http(base + "/no/such/path")
    check(status == 404 and isinstance(body, dict) and isinstance(body.get("error"), dict)
          and body["error"].get("code") == "unknown_path",
          "GET /no/such/path: %d %s (%s), want 404 unknown_path (JSON)" % (status, body, ctype))
    print("GET /no/such/path: 404 %s" % body["error"]["code"])
    status, body, _ = http(base + "/api/command", {"cmd": "stop"})
    check(status == 403 and isinstance(body, dict) and isinstance(body.get("error"), dict)
          and body["error"].get("code") == "control_off",
          "POST /api/command stop without control: %d %s, want 403 control_off" % (status, body))
    print("POST /api/command stop: 403 %s" % body["error"].get("code"))

    dev.call("Runtime.evaluate", expression="1")  # collects the events that came meanwhile
    for e in dev.console_errors:
        print("note: browser console: %s" % e)
    csp = [e for e in dev.console_errors if "Content Security Policy" in e]
    check(not csp, "the page breaks its Content-Security-Policy: %s" % csp[0] if csp else "")
    check(not dev.exceptions, "the page threw: %s" % "; ".join(map(str, dev.exceptions)))
    dev.close()

    check(daemon.poll() is None,
          "hystbenchd exited (%s):\n%s" % (daemon.returncode, tail(daemon_log)))
    code, out, _ = cli(args, socket_path, "status", "--json")
    check(code == 0 and json.loads(out).get("state") is not None,
          "hystbenchd does not answer status")
    print("figure first_paint_ms=%.0f scope_fps=%.1f screenshot_colours=%d runs_shown=%d"
          % (first_paint, fps, colours, shown))
    procs.stop(daemon)
    run_with_control(args, procs, tmp, websocket)


TOKEN = "test-token-0123456789abcdef"


def run_with_control(args, procs, tmp, websocket):
    """A second daemon with `[http] control = true` and a token file: the page's control panel
    refuses a wrong token, then starts a track with the right one, which ends in the list."""
    token_file = os.path.join(tmp, "http-token")
    with open(token_file, "w") as f:
        f.write(TOKEN + "\n")
    config = os.path.join(tmp, "control.toml")
    with open(config, "w") as f:
        if args.config:
            with open(args.config) as shipped:
                f.write(shipped.read())
        f.write("\n[http]\ncontrol = true\ntoken_file = %s\n" % json.dumps(token_file))
    socket_path = os.path.join(tmp, "control.sock")
    log = os.path.join(tmp, "hystbenchd-control.log")
    daemon = procs.start([args.daemon, "--config", config, "--socket", socket_path, "--log-dir",
                          os.path.join(tmp, "logs2"), "--model-dir", os.path.join(tmp, "models2"),
                          "--http", "127.0.0.1:0"] + args.daemon_arg, log)
    base = "http://" + http_address(args, socket_path, daemon, log)
    dev = launch_browser(procs, args.chromium, os.path.join(tmp, "b2"), websocket)
    dev.call("Page.enable")
    dev.call("Page.navigate", url=base + "/")
    # Until the navigation commits the tab still shows about:blank, which has no panel.
    dev.wait_for("(() => { const c = document.getElementById('control');"
                 " return !!c && !c.hidden; })()", 10, "the control panel")

    def press(token, button):
        dev.eval("(() => { const t = document.getElementById('token'); t.value = %s;"
                 " t.dispatchEvent(new Event('input'));"
                 " document.getElementById('trk-ref').value = 'sine';"
                 " document.getElementById('trk-freq').value = '5';"
                 " document.getElementById('trk-periods').value = '5';"
                 " document.getElementById(%s).click(); return 1; })()"
                 % (json.dumps(token), json.dumps(button)))

    press("not-the-token-at-all", "btn-track")
    dev.wait_for("document.getElementById('control-reply').textContent.indexOf('bad_token') >= 0",
                 5, "the refusal of a wrong token")
    check(cli_json(args, socket_path, "status", "--json").get("run") is None,
          "a wrong token started a run")
    press(TOKEN, "btn-track")
    dev.wait_for("document.getElementById('control-reply').textContent.indexOf('run_id') >= 0",
                 5, "the track's start from the page")
    dev.wait_for("!!document.querySelector('#runs tbody tr[data-run-id]')", 30,
                 "the page's track in the list")
    result = cli_json(args, socket_path, "status", "--json").get("last_result") or {}
    check(result.get("kind") == "track" and result.get("end") == "completed",
          "the page's track: %s" % json.dumps(result)[:300])
    print("control: a wrong token refused, the page's track %s %s"
          % (result.get("run_id"), result.get("end")))
    dev.close()
    check(daemon.poll() is None, "hystbenchd exited:\n%s" % tail(log))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.normpath(os.path.join(here, "..", "..", ".."))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--daemon", default=os.path.join(root, "build", "bin", "hystbenchd"),
                    help="hystbenchd (or a stand-in that takes the same options)")
    ap.add_argument("--cli", default=os.path.join(root, "build", "bin", "hystbench"))
    ap.add_argument("--daemon-arg", action="append", default=[],
                    help="one more argument for the daemon (repeatable)")
    ap.add_argument("--config", default=os.path.join(root, "config", "loopback.toml"),
                    help="the daemon's configuration (default: config/loopback.toml; '' = none)")
    ap.add_argument("--chromium", default=None, help="the browser (default: chromium on PATH)")
    ap.add_argument("--out", default=os.getcwd(), help="where the screenshot goes (default: .)")
    ap.add_argument("--keep", action="store_true", help="keep the temporary folder (logs)")
    args = ap.parse_args()

    args.chromium = args.chromium or find_chromium()
    if not args.chromium:
        print("SKIP: chromium not found (apt install chromium)")
        return SKIP
    websocket = import_websocket()
    for what in ("daemon", "cli"):
        path = getattr(args, what)
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            print("FAIL: %s %s is not an executable file" % (what, path))
            return 1

    procs = Processes()
    tmp = tempfile.mkdtemp(prefix="hb-browser-")
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(1))
    started = time.monotonic()
    try:
        run(args, procs, tmp, websocket)
        print("PASS (%.1f s)" % (time.monotonic() - started))
        return 0
    except Failure as e:
        print("FAIL: %s" % e)
        return 1
    except Exception as e:  # a broken connection or a crashed browser: a failure, said plainly
        print("FAIL: %s: %s" % (type(e).__name__, e))
        return 1
    finally:
        procs.stop_all()
        if args.keep:
            print("kept %s" % tmp)
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())

// hystbenchd's live view (docs/reference/web-view.md). Plain script, no build step; uPlot is
// loaded before it. One function (or a small group) per panel; all state lives in this closure.
(function () {
  "use strict";

  const SCOPE_SECONDS = 5;
  const POLL_MS = 2000;
  const SCOPE_HEIGHT = 300;
  const ERR_HEIGHT = 170;
  const COLORS = { y: "#1f5fbf", yr: "#d9480f", u: "#2b8a3e", err: "#862e9c" };
  const AXIS_COLORS = [COLORS, { y: "#0b7285", yr: "#c2255c", u: "#5c940d" },
    { y: "#5f3dc4", yr: "#e67700", u: "#087f5b" }];  // a run's plot, axis by axis

  const view = {
    frames: 0, samples: 0, lastSeq: null, runsShown: 0, firstPaintMs: null, connected: false,
  };
  window.hystbenchView = view;

  // ---------------------------------------------------------------- helpers

  const $ = (id) => document.getElementById(id);
  const finite = (v) => typeof v === "number" && isFinite(v);
  const utc = (iso) => (iso ? String(iso).replace("T", " ").replace("Z", "") : "—");
  const fmt = (v, digits) => (finite(v) ? v.toFixed(digits === undefined ? 3 : digits) : "—");

  function fmtNs(v) {
    if (!finite(v)) return "—";
    if (v < 1e3) return v.toFixed(0) + " ns";
    if (v < 1e6) return (v / 1e3).toPrecision(3) + " µs";
    if (v < 1e9) return (v / 1e6).toPrecision(3) + " ms";
    return (v / 1e9).toPrecision(3) + " s";
  }

  const text = (v) => (v == null || (typeof v === "number" && !isFinite(v)) ? "—" : String(v));

  function el(tag, attrs, children) {
    const e = document.createElement(tag);
    for (const k in attrs || {}) {
      if (k === "text") e.textContent = attrs[k];
      else if (k === "class") e.className = attrs[k];
      else e.setAttribute(k, attrs[k]);
    }
    for (const c of children || []) e.append(c);
    return e;
  }

  // JSON for reading: what the daemon sends as null (NaN, no value) shows as "—".
  const pretty = (obj) => JSON.stringify(obj, (k, v) => (v === null ? "—" : v), 2);

  async function getJSON(url) {
    const r = await fetch(url, { cache: "no-store" });
    const body = await r.json().catch(() => null);
    if (!r.ok) {
      const err = (body && body.error) || {};
      const e = new Error(err.message || r.status + " " + r.statusText);
      e.code = err.code;
      e.status = r.status;
      throw e;
    }
    return body;
  }

  function every(ms, fn) {
    fn();
    setInterval(fn, ms);
  }

  const plotWidth = (box) => Math.max(320, box.clientWidth || 800);

  // A legend value: at the cursor, or the newest value while the cursor is off the plot.
  const live = (digits) => (u, v, si, idx) => {
    const d = u.data[si];
    return fmt(idx === null || idx === undefined ? d[d.length - 1] : v, digits);
  };

  // ---------------------------------------------------------------- first paint

  function watchFirstPaint() {
    const take = (list) => {
      for (const e of list) {
        if (view.firstPaintMs === null || e.name === "first-paint") view.firstPaintMs = e.startTime;
      }
    };
    take(performance.getEntriesByType("paint"));
    try {
      new PerformanceObserver((l) => take(l.getEntries())).observe({ type: "paint", buffered: 1 });
    } catch (e) { /* an older browser: the entries read above are all there is */ }
  }

  // ---------------------------------------------------------------- header: bench and run

  function showView(v) {
    const hz = (f) => (finite(f) ? f.toLocaleString("en") + " Hz" : "—");
    const axes = v.axes.length > 1 ? " · " + v.axes.length + " axes" : "";
    $("driver").textContent = text(v.driver) + axes;
    $("rate").textContent = hz(v.rate_hz) + " · scope " + hz(v.scope_rate_hz);
    $("control").hidden = !v.control;
  }

  let modelKey = null;  // the model the panel shows, as the status names it
  let feedbackKey = null;  // the feedback loop the panel shows (status.feedback)
  let feedback = null;
  let shownModel = null;

  function showStatus(s) {
    const st = $("state");
    st.textContent = text(s.state);
    st.className = "state " + (s.state || "");
    $("fault-reason").hidden = !s.fault_reason;
    $("fault-reason").textContent = s.fault_reason ? "fault: " + s.fault_reason : "";
    if (s.run) {
      const r = s.run;
      const f = finite(r.fraction) ? r.fraction : finite(r.done) && r.total ? r.done / r.total
        : null;
      showProgress({ run_id: r.run_id, kind: r.kind, fraction: f, stage: r.stage }, f === null);
    } else {
      $("run").hidden = true;
    }
    showFaults(s.faults);
    const key = JSON.stringify((s.model && s.model.path) || (s.stage_model ? "stage" : null));
    const fb = JSON.stringify(s.feedback || null);
    if (fb !== feedbackKey) {
      feedbackKey = fb;
      feedback = s.feedback || null;
      if (key === modelKey) showModel(shownModel);
    }
    if (key !== modelKey) {
      modelKey = key;
      loadModel();
    }
  }

  let progressRun = null;

  // keepBar: a status without a fraction leaves the bar where the events put it.
  function showProgress(p, keepBar) {
    $("run").hidden = false;
    if (p.run_id !== progressRun) {
      progressRun = p.run_id;
      keepBar = false;
    }
    $("run-label").textContent = text(p.kind) + " " + text(p.run_id);
    if (!keepBar) {
      const f = finite(p.fraction) ? Math.min(1, Math.max(0, p.fraction)) : 0;
      $("run-bar").style.width = (100 * f).toFixed(1) + "%";
      $("run-fraction").textContent = finite(p.fraction) ? (100 * f).toFixed(1) + " %" : "—";
    }
    if (p.stage !== undefined) $("run-stage").textContent = p.stage || "";
  }

  function onBench(ev) {
    if (ev.event === "run.progress") {
      if (ev.run_id !== progressRun) loadStatus();
      showProgress(ev, ev.fraction === undefined);
    } else if (ev.event === "run.finished") {
      $("run").hidden = true;
      progressRun = null;
      loadStatus();
      loadRuns();
      loadModel();
      const id = ev.result && ev.result.run_id;
      if (id && !selectedRun) selectRun(id);
    }
  }

  const loadStatus = () => getJSON("/api/status").then(showStatus).catch(() => {});

  // ---------------------------------------------------------------- scope

  const scope = {
    axis: 0, cap: 2500, rings: [], next: null, dirty: false, plot: null, errPlot: null, dropped: 0,
  };

  const newRing = () => ({ t: [], y: [], yr: [], u: [] });

  function scopeOptions(width) {
    return {
      width: width, height: SCOPE_HEIGHT,
      cursor: { sync: { key: "scope" } },
      scales: { x: { time: false }, um: { auto: true }, V: { auto: true } },
      axes: [
        { label: "t [s]", size: 36 },
        { scale: "um", label: "y, yr [um]", size: 56 },
        { scale: "V", side: 1, label: "u [V]", size: 56, grid: { show: false } },
      ],
      series: [
        { label: "t", value: live(4) },
        { label: "y [um]", scale: "um", stroke: COLORS.y, width: 1.5, value: live(3) },
        { label: "yr [um]", scale: "um", stroke: COLORS.yr, width: 1.5, dash: [6, 3],
          value: live(3) },
        { label: "u [V]", scale: "V", stroke: COLORS.u, width: 1, value: live(2) },
      ],
    };
  }

  // Symmetric about zero, so that the sign of the error reads at a glance; ±1 um with no error.
  function errRange(u, min, max) {
    const m = Math.max(Math.abs(finite(min) ? min : 0), Math.abs(finite(max) ? max : 0));
    const r = m > 0 ? uPlot.rangeNum(-m, m, 0.1, true) : [-1, 1];
    const h = Math.max(Math.abs(r[0]), Math.abs(r[1]));
    return [-h, h];
  }

  function errOptions(width) {
    const blank = { scale: "um", side: 1, size: 56, label: "\u00a0", values: () => [] };
    return {
      width: width, height: ERR_HEIGHT,
      cursor: { sync: { key: "scope" } },
      scales: { x: { time: false }, um: { range: errRange } },
      axes: [{ size: 30 }, { scale: "um", label: "yr − y [um]", size: 56 }, blank],
      series: [
        { label: "t", value: live(4) },
        { label: "error yr − y [um]", scale: "um", stroke: COLORS.err, width: 1, value: live(3) },
      ],
    };
  }

  function initScope(v) {
    scope.cap = Math.ceil(SCOPE_SECONDS * (v.scope_rate_hz || 500)) + 1;
    scope.rings = v.axes.map(newRing);
    const pick = $("axis");
    v.axes.forEach((n, i) => pick.append(el("option", { value: i, text: n || "axis " + (i + 1) })));
    $("axis-pick").hidden = v.axes.length <= 1;
    pick.addEventListener("change", () => {
      scope.axis = Number(pick.value);
      scope.dirty = true;
      requestDraw();
    });
    const w = plotWidth($("scope"));
    scope.plot = new uPlot(scopeOptions(w), [[], [], [], []], $("scope"));
    scope.errPlot = new uPlot(errOptions(w), [[], []], $("scope-err"));
    window.addEventListener("resize", () => {
      const w2 = plotWidth($("scope"));
      scope.plot.setSize({ width: w2, height: SCOPE_HEIGHT });
      scope.errPlot.setSize({ width: w2, height: ERR_HEIGHT });
    });
  }

  function pushSamples(d) {
    const n = d.y && d.y[0] ? d.y[0].length : 0;
    if (!n) return;
    if (scope.next !== null && d.seq < scope.next) scope.rings = scope.rings.map(newRing);
    const gap = scope.next !== null && d.seq > scope.next;  // started again from the newest
    d.axes.forEach((name, a) => {
      const r = scope.rings[a] || (scope.rings[a] = newRing());
      if (gap) for (const k in r) r[k].push(k === "t" ? d.t0 - d.dt / 2 : null);
      for (let i = 0; i < n; i++) {
        r.t.push(d.t0 + i * d.dt);
        r.y.push(d.y[a][i]);
        r.yr.push(d.yr[a] ? d.yr[a][i] : null);
        r.u.push(d.u[a][i]);
      }
      const over = r.t.length - scope.cap;
      if (over > 0) for (const k in r) r[k].splice(0, over);
    });
    scope.next = d.seq + n;
    scope.dropped = d.dropped;
    view.samples += n;
    view.lastSeq = d.seq + n - 1;
    scope.dirty = true;
    requestDraw();
  }

  let drawPending = false;

  function requestDraw() {
    if (drawPending) return;
    drawPending = true;
    requestAnimationFrame(drawScope);
  }

  // At most once an animation frame, and only when samples came since the last.
  function drawScope() {
    drawPending = false;
    if (!scope.dirty || !scope.plot) return;
    scope.dirty = false;
    const r = scope.rings[scope.axis] || newRing();
    const err = r.y.map((y, i) => (finite(y) && finite(r.yr[i]) ? r.yr[i] - y : null));
    const x = { min: (r.t.length ? r.t[r.t.length - 1] : SCOPE_SECONDS) - SCOPE_SECONDS };
    x.max = x.min + SCOPE_SECONDS;
    scope.plot.batch(() => {
      scope.plot.setData([r.t, r.y, r.yr, r.u], false);
      scope.plot.setScale("x", x);
    });
    scope.errPlot.batch(() => {
      scope.errPlot.setData([r.t, err], false);
      scope.errPlot.setScale("x", x);
    });
    // The legends read the newest values while the cursor is off the plots.
    for (const p of [scope.plot, scope.errPlot]) {
      if (p.cursor.idx == null) p.setLegend({ idx: null });
    }
    view.frames++;
    $("scope-info").textContent = `seq ${text(view.lastSeq)} · dropped ${text(scope.dropped)}`;
  }

  // ---------------------------------------------------------------- stream

  function connectStream() {
    const es = new EventSource("/api/stream");  // reconnects by itself
    const conn = (on) => {
      view.connected = on;
      $("conn").textContent = on ? "live" : "reconnecting";
      $("conn").className = "conn " + (on ? "on" : "off");
    };
    const handle = (what, fn) => (m) => {
      try {
        fn(JSON.parse(m.data));
      } catch (e) {
        console.error(what, e);
      }
    };
    es.onopen = () => conn(true);
    es.onerror = () => conn(false);
    es.addEventListener("scope", handle("scope frame", (d) => {
      if (!view.connected) conn(true);
      pushSamples(d);
    }));
    es.addEventListener("bench", handle("bench event", onBench));
  }

  // ---------------------------------------------------------------- runs

  let selectedRun = null;
  let runPlot = null;

  function runRow(r) {
    const end = text(r.end) + (r.reason ? ": " + r.reason : "");
    const rms = finite(r.rms_error_percent) ? fmt(r.rms_error_percent, 3) + " %" : "—";
    const tr = el("tr", { "data-run-id": r.run_id, class: r.run_id === selectedRun ? "sel" : "" }, [
      el("td", { class: "id", text: text(r.run_id) }),
      el("td", { text: text(r.kind) }),
      el("td", { class: "end " + (r.end || ""), text: end }),
      el("td", { class: "num", text: utc(r.finished) }),
      el("td", { class: "num r", text: rms }),
    ]);
    tr.addEventListener("click", () => selectRun(r.run_id));
    return tr;
  }

  function showRuns(list) {
    const rows = list.map(runRow);
    $("runs").tBodies[0].replaceChildren(...rows);
    view.runsShown = rows.length;
    $("runs-empty").hidden = rows.length > 0;
  }

  const loadRuns = () => getJSON("/api/runs").then((r) => showRuns(r.runs || [])).catch(() => {});

  async function selectRun(id) {
    selectedRun = id;
    for (const tr of $("runs").tBodies[0].rows) tr.classList.toggle("sel", tr.dataset.runId === id);
    $("run-detail").hidden = false;
    $("run-title").textContent = id;
    $("run-result").textContent = "loading…";
    const url = "/api/runs/" + encodeURIComponent(id);
    const [res, smp] = await Promise.allSettled([
      getJSON(url), getJSON(url + "/samples?points=2000")]);
    if (selectedRun !== id) return;
    $("run-result").textContent =
      res.status === "fulfilled" ? pretty(res.value) : "— (" + res.reason.message + ")";
    plotRun(smp.status === "fulfilled" ? smp.value : null, smp.reason);
  }

  function plotRun(s, error) {
    const box = $("run-plot");
    if (runPlot) runPlot.destroy();
    runPlot = null;
    box.replaceChildren();
    if (!s || !s.axes || !s.axes.length) {
      const why = "no sample log" + (error ? " (" + error.message + ")" : "");
      box.append(el("p", { class: "muted", text: why }));
      return;
    }
    const series = [{ label: "t", value: (u, v) => fmt(v, 4) }];
    const data = [s.t];
    s.axes.forEach((ax, i) => {
      const n = s.axes.length > 1 ? " " + (ax.name || i + 1) : "";
      const c = AXIS_COLORS[i % AXIS_COLORS.length];
      const val = (digits) => (u, v) => fmt(v, digits);
      series.push(
        { label: `yr${n} [um]`, scale: "um", stroke: c.yr, dash: [6, 3], width: 1.2,
          value: val(3) },
        { label: `y${n} [um]`, scale: "um", stroke: c.y, width: 1.2, value: val(3) },
        { label: `u${n} [V]`, scale: "V", stroke: c.u, width: 1, value: val(2) });
      data.push(ax.yr, ax.y, ax.u);
    });
    const axes = [
      { label: "t [s]", size: 36 },
      { scale: "um", label: "yr, y [um]", size: 56 },
      { scale: "V", side: 1, label: "u [V]", size: 56, grid: { show: false } },
    ];
    const scales = { x: { time: false } };
    runPlot = new uPlot({ width: plotWidth(box), height: 260, scales, axes, series }, data, box);
  }

  // ---------------------------------------------------------------- model

  function modelLoop(m) {
    const n = (o) => (o && o.thresholds ? o.thresholds.length : 0);
    const dz = m.deadzone ? " + " + n(m.deadzone) + " dead zones" : "";
    if (m.preisach) return "Preisach plane, " + text(m.preisach.cells) + " cells";
    if (m.coupled_play) return "coupled play operators" + dz;
    if (m.play) return n(m.play) + " play operators" + dz;
    return null;
  }

  function modelParts(m) {
    const parts = [];
    const rate = m.rate || (m.preisach && m.preisach.rate);
    if (rate) parts.push("rate law (" + text(rate.law) + ")");
    if (m.creep) {
      const tau = (m.creep.time_constants_s || []).map((t) => fmt(t, 3) + " s");
      parts.push("creep (" + tau.join(", ") + ")");
    }
    const d = m.dynamics;
    if (d) {
      parts.push(`dynamics (${fmt(d.natural_frequency_hz, 0)} Hz, ζ ${fmt(d.damping_ratio)})`);
    }
    if (finite(m.delay_s)) parts.push("delay " + fmt(m.delay_s * 1e6, 0) + " µs");
    if (m.frequency_response) parts.push("measured frequency response");
    const ext = m.identification && m.identification.extension;
    if (ext && Array.isArray(ext.parts)) {
      const took = ext.parts.filter((p) => p.adopted).map((p) => p.part || p.name).filter(Boolean);
      if (took.length) parts.push("identify added: " + took.join(", "));
    }
    return parts;
  }

  // The loop the compensator closes around the model (the last track, tune or frf's design).
  function feedbackRows() {
    const f = feedback;
    if (!f) return [["feedback", "none designed yet"]];
    return [
      ["feedback", text(f.compensator) + (f.gains ? " (" + text(f.gains) + " gains)" : "")],
      ["crossover", finite(f.crossover_hz) ? fmt(f.crossover_hz, 0) + " Hz" : null],
      ["bandwidth", finite(f.bandwidth_hz) ? fmt(f.bandwidth_hz, 0) + " Hz" : null],
      ["limited by", f.limited_by],
    ];
  }

  // A stage's model: one row per axis.
  function stageRows(r) {
    const rows = [];
    for (const name of r.axes_order || Object.keys(r.axes)) {
      const a = r.axes[name] || {};
      const parts = [text(a.model), text(a.operators) + " operators"];
      if (a.creep) parts.push("creep");
      if (finite(a.delay_samples) && a.delay_samples > 0) parts.push(a.delay_samples + " ticks delay");
      parts.push("held-out " + fmt(a.heldout_rms_error_percent, 3) + " %");
      rows.push(["axis " + name, parts.join(" · ")]);
    }
    rows.push(["coupling", r.coupling ? "measured between the axes" : "none"]);
    return rows;
  }

  function showModel(r) {
    shownModel = r;
    const body = $("model-body");
    const m = r && (r.model || (r.type ? r : null));
    const stage = r && !m && r.axes && typeof r.axes === "object";
    if (!m && !stage) {
      body.replaceChildren(el("p", { class: "muted", text: "no model loaded" }));
      return;
    }
    let rows;
    if (stage) {
      rows = stageRows(r).concat([["identify", r.run_id]]);
    } else {
      const range = Array.isArray(m.input_range) ? m.input_range.map((v) => fmt(v, 3)).join(" … ")
        : null;
      rows = [
        ["family", m.type],
        ["loop", modelLoop(m)],
        ["parts", modelParts(m).join("; ") || "none"],
        ["units", m.units ? text(m.units.input) + " → " + text(m.units.output) : null],
        ["input range", range],
        ["file", r.path],
      ];
    }
    rows = rows.concat(feedbackRows());
    const dl = el("dl", { class: "kv" });
    for (const [k, v] of rows) dl.append(el("dt", { text: k }), el("dd", { text: text(v) }));
    const summary = el("summary", { text: "raw JSON" });
    body.replaceChildren(dl, el("details", {}, [summary, el("pre", { text: pretty(r) })]));
  }

  function loadModel() {
    return getJSON("/api/model").then(showModel).catch((e) => {
      if (e.code === "no_model" || e.status === 404 || e.status === 409) return showModel(null);
      if (!e.status) return;  // no daemon: keep what is shown
      $("model-body").replaceChildren(el("p", { class: "muted", text: "— (" + e.message + ")" }));
    });
  }

  // ---------------------------------------------------------------- timing

  // One histogram as CSS bars on a log axis (decades), bar heights log(1 + count).
  function histogram(box, title, h) {
    const s = (h && h.summary) || {};
    const bins = (h && h.bins) || [];
    const figures = ["p50", "p99", "max"].map((k) => k + " " + fmtNs(s[k])).join(" · ");
    const head = el("div", { class: "hist-head" }, [
      el("b", { text: title }),
      el("span", { class: "num", text: figures + " · n " + text(s.count) }),
    ]);
    if (!bins.length) {
      box.replaceChildren(head, el("p", { class: "muted", text: "no samples" }));
      return;
    }
    const first = Math.min(bins[0][0], finite(s.min) ? s.min : Infinity);
    const last = Math.max(bins[bins.length - 1][1], finite(s.max) ? s.max : 0);
    const lo = Math.floor(Math.log10(Math.max(1, first)));
    const hi = Math.max(lo + 1, Math.ceil(Math.log10(Math.max(10, last))));
    const pos = (v) => (100 * (Math.log10(Math.max(v, 1)) - lo)) / (hi - lo);
    const x = (v) => Math.min(100, Math.max(0, pos(v)));
    const top = Math.log10(1 + Math.max(...bins.map((b) => b[2])));
    const area = el("div", { class: "hist-area" });
    for (const [from, to, count] of bins) {
      const bar = el("div", { class: "hbar", title: `${fmtNs(from)} – ${fmtNs(to)}: ${count}` });
      bar.style.left = x(from) + "%";
      bar.style.width = Math.max(0.3, x(to) - x(from)) + "%";
      bar.style.height = (100 * Math.log10(1 + count)) / top + "%";
      area.append(bar);
    }
    for (const k of ["p50", "p99", "max"]) {
      if (!finite(s[k])) continue;
      const cls = "hmark " + k + (x(s[k]) > 90 ? " left" : "");  // label left of a mark at the end
      const label = el("span", { text: k });
      const mark = el("div", { class: cls, title: k + " " + fmtNs(s[k]) }, [label]);
      mark.style.left = x(s[k]) + "%";
      area.append(mark);
    }
    const axis = el("div", { class: "hist-axis" });
    for (let d = lo; d <= hi; d++) {
      const label = ["1", "10", "100"][d % 3] + " " + ["ns", "µs", "ms", "s"][Math.floor(d / 3)];
      const tick = el("span", { text: label });
      tick.style.left = (100 * (d - lo)) / (hi - lo) + "%";
      axis.append(tick);
    }
    box.replaceChildren(head, area, axis);
  }

  function showTiming(t) {
    histogram($("hist-exec"), "execution", t.exec_ns);
    histogram($("hist-wake"), "wake-up latency", t.wake_latency_ns);
    const counts = ["ticks", "overruns", "skipped"].map((k) => k + " " + text(t[k]));
    $("timing-info").textContent = counts.join(" · ");
    $("timing-info").classList.toggle("warn", t.overruns > 0);
  }

  const loadTiming = () => getJSON("/api/timing").then(showTiming).catch(() => {});

  // ---------------------------------------------------------------- faults

  function showFaults(list) {
    const body = $("faults-body");
    if (!Array.isArray(list) || !list.length) {
      body.replaceChildren(el("p", { class: "muted", text: "no faults" }));
      return;
    }
    const rows = list.slice().reverse().map((f) => el("tr", {}, [
      el("td", { class: "num", text: utc(f.time) }),
      el("td", { class: "id", text: text(f.run_id) }),
      el("td", { text: text(f.reason) }),
    ]));
    const head = el("tr", {}, ["time (UTC)", "run", "reason"].map((h) => el("th", { text: h })));
    const parts = [el("thead", {}, [head]), el("tbody", {}, rows)];
    body.replaceChildren(el("table", { class: "faults" }, parts));
  }

  // ---------------------------------------------------------------- control

  async function sendCommand(cmd, params) {
    const reply = $("control-reply");
    reply.className = "reply";
    reply.textContent = cmd + " …";
    try {
      const r = await fetch("/api/command", {
        method: "POST",
        headers: {
          "Content-Type": "application/json",
          Authorization: "Bearer " + $("token").value.trim(),
        },
        body: JSON.stringify({ cmd: cmd, params: params || {} }),
      });
      const body = await r.json().catch(() => null);
      if (r.ok && body && body.ok !== false) {
        reply.textContent = cmd + ": " + pretty(body.result !== undefined ? body.result : body);
        return;
      }
      const e = (body && body.error) || {};
      reply.className = "reply refused";
      reply.textContent = `${cmd} refused (${r.status} ${text(e.code)}): ${text(e.message)}`;
    } catch (e) {
      reply.className = "reply refused";
      reply.textContent = cmd + ": " + e.message;
    }
  }

  function initControl() {
    const token = $("token");
    token.value = sessionStorage.getItem("hystbench-token") || "";
    const keep = () => sessionStorage.setItem("hystbench-token", token.value.trim());
    token.addEventListener("input", keep);
    $("btn-identify").addEventListener("click", () => sendCommand("identify"));
    $("btn-track").addEventListener("click", () => sendCommand("track", {
      reference: $("trk-ref").value,
      frequency_hz: Number($("trk-freq").value),
      periods: Number($("trk-periods").value),
      compensator: $("trk-comp").value,
    }));
    $("btn-stop").addEventListener("click", () => sendCommand("stop"));
    $("btn-abort").addEventListener("click", () => sendCommand("abort"));
  }

  // ---------------------------------------------------------------- start

  async function start() {
    let v;
    try {
      v = await getJSON("/api/view");
    } catch (e) {
      $("state").textContent = "no daemon (" + e.message + ")";
      setTimeout(start, POLL_MS);
      return;
    }
    showView(v);
    initScope(v);
    if (v.control) initControl();
    connectStream();
    for (const load of [loadStatus, loadRuns, loadTiming]) every(POLL_MS, load);
  }

  watchFirstPaint();
  start();
})();

"use strict";
// The monitor page: node cards, traces, platform view, bus table, fed by
// the state embedded in the page, then by /api/events.
(function () {
  const COL = CONFIG.colours;
  const QUANT = [
    { name: "joint position", unit: "mm", digits: 3 },
    { name: "following error", unit: "µm", digits: 2 },
    { name: "torque command", unit: "N·m", digits: 3 },
  ];
  const KEEP = 60; // s of history kept in the page
  // series[q][axis] = {t: [], v: []}, bus time (s), oldest first.
  const series = QUANT.map(() => [0, 1, 2].map(() => ({ t: [], v: [] })));
  let trail = []; // [t, x, y, z] mm
  let planned = [];
  let latest = null; // latest state
  let points = 0; // samples taken in since load
  let events = 0;
  let paused = false;
  let pausedAt = null;
  let zoom = 1;
  const $ = (id) => document.getElementById(id);

  function fmt(x, d) {
    return x === null || x === undefined || !isFinite(x) ? "–" : Number(x).toFixed(d);
  }
  function esc(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);
  }

  function take(ev) {
    latest = ev;
    if (ev.traces) {
      ev.traces.forEach((axes, q) => axes.forEach((samples, a) => {
        const s = series[q][a];
        for (const [t, v] of samples) {
          if (s.t.length && t <= s.t[s.t.length - 1]) continue;
          s.t.push(t); s.v.push(v); points++;
        }
        const cut = (s.t.length ? s.t[s.t.length - 1] : 0) - KEEP;
        let k = 0;
        while (k < s.t.length && s.t[k] < cut) k++;
        if (k) { s.t.splice(0, k); s.v.splice(0, k); }
      }));
    }
    if (ev.trail) {
      for (const p of ev.trail) {
        if (!trail.length || p[0] > trail[trail.length - 1][0]) trail.push(p);
      }
      const cut = (trail.length ? trail[trail.length - 1][0] : 0) - 10;
      trail = trail.filter((p) => p[0] >= cut);
    }
    if (ev.planned) planned = ev.planned;
    $("traces").dataset.points = String(points);
    $("traces").dataset.events = String(events);
    render();
  }

  // ---------- node cards ----------
  function card(n) {
    const state = n.state || "silent";
    const fault = n.fault && n.fault.code ? `${esc(n.fault.name)} (${n.fault.code}): ${esc(n.fault.hint)}` : "";
    const age = n.heartbeat_age_s === null ? "never" : `${fmt(n.heartbeat_age_s, 2)} s`;
    const be = n.bus_errors || { tx: 0, rx: 0, rejects: 0 };
    const yes = (b) => (b ? "yes" : "no");
    return `<header><h2>Axis ${n.axis}</h2><span class="axis">node ${n.id}</span>` +
      (n.stale ? `<span class="badge">stale</span>` : "") +
      `<span class="state st-${esc(state)}">${esc(state)}</span></header>` +
      `<dl>` +
      `<dt>position</dt><dd>${fmt(n.joint_position_mm, 3)} mm</dd>` +
      `<dt>homing</dt><dd>${esc(n.homing)}</dd>` +
      `<dt>held</dt><dd>${yes(n.held)}</dd><dt>override</dt><dd>${yes(n.override)}</dd>` +
      `<dt>queue</dt><dd>${n.queue_depth}</dd><dt>sync</dt><dd>${n.synced ? "synced" : "not synced"}</dd>` +
      `<dt>heartbeat</dt><dd>${age} ago</dd><dt>bus errors</dt><dd>tx ${be.tx} · rx ${be.rx} · rej ${be.rejects}</dd>` +
      `<dt>foll. error</dt><dd>${fmt(n.following_error_um, 2)} µm</dd><dt>torque</dt><dd>${fmt(n.torque_nm, 3)} N·m</dd>` +
      `</dl><div class="fault">${fault}</div>`;
  }
  function renderNodes(s) {
    const box = $("nodes");
    s.nodes.forEach((n, i) => {
      let el = box.children[i];
      if (!el) { el = document.createElement("article"); el.className = "node"; box.appendChild(el); }
      el.style.borderTopColor = COL[i];
      el.classList.toggle("stale", !!n.stale);
      el.dataset.state = n.state || "";
      el.innerHTML = card(n);
    });
  }

  // ---------- charts ----------
  function nice(span, n) {
    const raw = span / n, p = Math.pow(10, Math.floor(Math.log10(raw))), f = raw / p;
    return (f < 1.5 ? 1 : f < 3.5 ? 2 : f < 7.5 ? 5 : 10) * p;
  }
  function sized(c) {
    const r = window.devicePixelRatio || 1, w = c.clientWidth, h = c.clientHeight;
    if (c.width !== Math.round(w * r) || c.height !== Math.round(h * r)) {
      c.width = Math.round(w * r); c.height = Math.round(h * r);
    }
    const g = c.getContext("2d");
    g.setTransform(r, 0, 0, r, 0, 0);
    return [g, w, h];
  }
  function windowS() { return Number($("window").value) / zoom; }
  function now() {
    if (paused && pausedAt !== null) return pausedAt;
    return latest ? latest.time_s : 0;
  }
  function drawChart(q) {
    const [g, w, h] = sized($("c" + q));
    const L = 64, R = 12, T = 20, B = 30, pw = w - L - R, ph = h - T - B;
    const t1 = now(), t0 = t1 - windowS();
    let lo = Infinity, hi = -Infinity;
    for (const s of series[q]) {
      for (let k = 0; k < s.t.length; k++) {
        if (s.t[k] < t0 || s.t[k] > t1) continue;
        if (s.v[k] < lo) lo = s.v[k];
        if (s.v[k] > hi) hi = s.v[k];
      }
    }
    if (!isFinite(lo)) { lo = -1; hi = 1; }
    if (hi - lo < 1e-9) { lo -= 0.5; hi += 0.5; }
    const pad = (hi - lo) * 0.08; lo -= pad; hi += pad;
    const X = (t) => L + ((t - t0) / (t1 - t0)) * pw, Y = (v) => T + (1 - (v - lo) / (hi - lo)) * ph;
    g.clearRect(0, 0, w, h);
    g.font = "11px system-ui, sans-serif"; g.lineWidth = 1;
    const ys = nice(hi - lo, 4);
    g.textAlign = "right"; g.textBaseline = "middle";
    for (let v = Math.ceil(lo / ys) * ys; v <= hi; v += ys) {
      g.strokeStyle = "#e4e4e4"; g.beginPath(); g.moveTo(L, Y(v)); g.lineTo(L + pw, Y(v)); g.stroke();
      g.fillStyle = "#505050"; g.fillText(Math.abs(v) < ys / 1e6 ? "0" : v.toPrecision(4).replace(/\.?0+$/, ""), L - 5, Y(v));
    }
    const xs = nice(t1 - t0, 6);
    g.textAlign = "center"; g.textBaseline = "top";
    for (let d = 0; d <= t1 - t0 + 1e-9; d += xs) {
      const x = X(t1 - d);
      g.strokeStyle = "#e4e4e4"; g.beginPath(); g.moveTo(x, T); g.lineTo(x, T + ph); g.stroke();
      g.fillStyle = "#505050"; g.fillText(d === 0 ? "0" : "−" + Number(d.toPrecision(3)), x, T + ph + 4);
    }
    g.strokeStyle = "#303030"; g.strokeRect(L, T, pw, ph);
    g.save(); g.beginPath(); g.rect(L, T, pw, ph); g.clip();
    series[q].forEach((s, a) => {
      g.strokeStyle = COL[a]; g.lineWidth = 1.6; g.beginPath();
      let first = true;
      for (let k = 0; k < s.t.length; k++) {
        if (s.t[k] < t0 - 1 || s.t[k] > t1 + 1) continue;
        const x = X(s.t[k]), y = Y(s.v[k]);
        if (first) { g.moveTo(x, y); first = false; } else g.lineTo(x, y);
      }
      g.stroke();
    });
    g.restore();
    g.fillStyle = "#303030"; g.font = "600 12px system-ui, sans-serif"; g.textAlign = "left"; g.textBaseline = "top";
    g.fillText(`${QUANT[q].name} (${QUANT[q].unit})`, L, 3);
    g.font = "11px system-ui, sans-serif"; g.textAlign = "right"; g.fillStyle = "#707070";
    g.fillText("time before latest sample (s)", L + pw, 3);
  }

  // ---------- 3-D view ----------
  let az = 0.55, el = 0.4;
  function draw3d() {
    const [g, w, h] = sized($("view3d"));
    g.clearRect(0, 0, w, h);
    const pts = trail.map((p) => [p[1], p[2], p[3]]).concat(planned);
    const cur = latest && latest.platform_mm;
    if (cur) pts.push(cur);
    g.font = "12px system-ui, sans-serif"; g.fillStyle = "#707070"; g.textAlign = "center";
    if (!pts.length) { g.fillText("platform position unknown (every axis homed and reporting)", w / 2, h / 2); return; }
    const lo = [0, 1, 2].map((i) => Math.min(...pts.map((p) => p[i])));
    const hi = [0, 1, 2].map((i) => Math.max(...pts.map((p) => p[i])));
    const c = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
    const half = Math.max(5, ...[0, 1, 2].map((i) => (hi[i] - lo[i]) / 2)) * 1.15;
    const ca = Math.cos(az), sa = Math.sin(az), ce = Math.cos(el), se = Math.sin(el);
    const s = Math.min(w, h) / (3.6 * half);
    const P = (p) => {
      const x = (p[0] - c[0]), y = (p[1] - c[1]), z = (p[2] - c[2]);
      const u = ca * x - sa * y, d = sa * x + ca * y;
      return [w / 2 + u * s, h / 2 - (z * ce - d * se) * s];
    };
    const line = (a, b, col, dash) => {
      const A = P(a), B2 = P(b);
      g.strokeStyle = col; g.setLineDash(dash || []); g.beginPath(); g.moveTo(A[0], A[1]); g.lineTo(B2[0], B2[1]); g.stroke();
      g.setLineDash([]);
    };
    // Box around the data, floor grid, axis labels.
    const b = [c[0] - half, c[1] - half, c[2] - half], e = [c[0] + half, c[1] + half, c[2] + half];
    g.lineWidth = 1;
    for (let k = 0; k <= 4; k++) {
      const f = k / 4;
      line([b[0] + f * 2 * half, b[1], b[2]], [b[0] + f * 2 * half, e[1], b[2]], "#e4e4e4");
      line([b[0], b[1] + f * 2 * half, b[2]], [e[0], b[1] + f * 2 * half, b[2]], "#e4e4e4");
    }
    // Cartesian axes in grey: the colours belong to the joints.
    line([b[0], b[1], b[2]], [e[0], b[1], b[2]], "#505050");
    line([b[0], b[1], b[2]], [b[0], e[1], b[2]], "#505050");
    line([b[0], b[1], b[2]], [b[0], b[1], e[2]], "#505050");
    g.fillStyle = "#505050"; g.font = "11px system-ui, sans-serif";
    const lab = (p, t) => { const q = P(p); g.fillText(t, q[0], q[1]); };
    lab([e[0] + half * 0.2, b[1], b[2]], `x ${fmt(b[0], 0)}…${fmt(e[0], 0)} mm`);
    lab([b[0], e[1] + half * 0.2, b[2]], `y ${fmt(b[1], 0)}…${fmt(e[1], 0)} mm`);
    lab([b[0], b[1], e[2] + half * 0.1], `z ${fmt(b[2], 0)}…${fmt(e[2], 0)} mm`);
    // Planned path, trail (fading), current position.
    if (planned.length > 1) {
      g.lineWidth = 1.5; g.strokeStyle = "#707070"; g.setLineDash([5, 4]); g.beginPath();
      planned.forEach((p, k) => { const q = P(p); if (k) g.lineTo(q[0], q[1]); else g.moveTo(q[0], q[1]); });
      g.stroke(); g.setLineDash([]);
    }
    g.lineWidth = 2.5;
    for (let k = 1; k < trail.length; k++) {
      const A = P(trail[k - 1].slice(1)), B2 = P(trail[k].slice(1));
      g.strokeStyle = `rgba(192, 16, 16, ${0.15 + 0.85 * k / trail.length})`;
      g.beginPath(); g.moveTo(A[0], A[1]); g.lineTo(B2[0], B2[1]); g.stroke();
    }
    if (cur) {
      const q = P(cur);
      g.fillStyle = "#c01010"; g.beginPath(); g.arc(q[0], q[1], 5, 0, 2 * Math.PI); g.fill();
    }
  }
  (function drag() {
    const cv = $("view3d");
    let from = null;
    cv.addEventListener("pointerdown", (e) => { from = [e.clientX, e.clientY, az, el]; cv.setPointerCapture(e.pointerId); });
    cv.addEventListener("pointermove", (e) => {
      if (!from) return;
      az = from[2] + (e.clientX - from[0]) * 0.01;
      el = Math.max(-1.5, Math.min(1.5, from[3] + (e.clientY - from[1]) * 0.01));
      draw3d();
    });
    cv.addEventListener("pointerup", () => { from = null; });
  })();

  // ---------- header, bus ----------
  function renderInfo(s) {
    $("clock").textContent = `t = ${fmt(s.time_s, 2)} s`;
    const v = [...new Set(s.nodes.filter((n) => n.protocol_version !== null).map((n) => n.protocol_version))];
    $("versions").textContent = `protocol v${s.host_protocol_version} (host) · ` +
      (v.length ? `v${v.join(", v")} (drives)` : "drives silent") + " · firmware version: not on the bus";
    const bus = s.bus;
    $("load").textContent = `${fmt(bus.frames_per_s, 0)} frames/s · load ${fmt(bus.load * 100, 1)} % of ${bus.nominal_bps / 1e6} Mbit/s`;
    const rows = Object.entries(bus.rates).sort((a, b) => b[1] - a[1]);
    $("rates").innerHTML = rows.map(([k, r]) => `<tr><td>${esc(k)}</td><td class="n">${fmt(r, 0)} /s</td></tr>`).join("") +
      `<tr><td>frames since start</td><td class="n">${bus.frames_total}</td></tr>`;
    $("platform").textContent = s.platform_mm ? `(${s.platform_mm.map((x) => fmt(x, 2)).join(", ")}) mm` : "unknown";
  }

  let queued = false;
  function render() {
    if (queued) return;
    queued = true;
    requestAnimationFrame(() => {
      queued = false;
      if (!latest) return;
      renderNodes(latest);
      renderInfo(latest);
      for (let q = 0; q < 3; q++) drawChart(q);
      draw3d();
    });
  }

  // ---------- controls ----------
  $("legend").innerHTML = [1, 2, 3].map((a) => `<span><i style="background:${COL[a - 1]}"></i>axis ${a}</span>`).join("");
  $("window").addEventListener("change", () => {
    zoom = 1;
    $("csv").href = `/api/trace.csv?window=${$("window").value}`;
    render();
  });
  $("pause").addEventListener("click", () => {
    paused = !paused;
    pausedAt = paused ? now() : null;
    $("pause").classList.toggle("on", paused);
    $("pause").textContent = paused ? "Resume view" : "Pause";
    render();
  });
  $("unzoom").addEventListener("click", () => { zoom = 1; render(); });
  for (let q = 0; q < 3; q++) {
    $("c" + q).addEventListener("wheel", (e) => {
      e.preventDefault();
      zoom = Math.max(1, Math.min(50, zoom * (e.deltaY < 0 ? 1.25 : 0.8)));
      render();
    }, { passive: false });
  }
  window.addEventListener("resize", render);
  if (CONFIG.control) {
    $("controlpanel").hidden = false;
    document.querySelectorAll("#controlpanel button").forEach((b) => b.addEventListener("click", () => {
      fetch(`/api/${b.dataset.act}`, { method: "POST" })
        .then((r) => r.text().then((t) => { $("ctlmsg").textContent = `${r.status}: ${t.trim()}`; }))
        .catch((e) => { $("ctlmsg").textContent = String(e); });
    }));
  }

  // ---------- data ----------
  take(INITIAL);
  // The browser reconnects a dropped stream by itself, not a refused one
  // (503: too many streams): that one is opened again here.
  const connect = () => {
    const es = new EventSource("/api/events");
    es.onopen = () => { $("link").textContent = `${CONFIG.replay ? "replay" : "live"} · ${CONFIG.event_hz} Hz`; $("link").className = "pill ok"; };
    es.onerror = () => {
      $("link").textContent = "reconnecting…"; $("link").className = "pill bad";
      if (es.readyState === EventSource.CLOSED) setTimeout(connect, 2000);
    };
    es.onmessage = (m) => { events++; take(JSON.parse(m.data)); };
  };
  connect();
  window.triquintMonitor = { points: () => points, events: () => events, series: series };
})();

// kinprop workbench: plain JavaScript over the JSON API (/api/...), plotly.js for 3D and curves.
"use strict";

const SESSION = (() => {
  let id = sessionStorage.getItem("kinprop-session");
  if (!id) {
    id = (crypto.randomUUID ? crypto.randomUUID() : String(Math.random()).slice(2));
    sessionStorage.setItem("kinprop-session", id);
  }
  return id;
})();

const $ = (id) => document.getElementById(id);
let state = null;          // GET /api/state
let curve = null;          // the last sweep drawn: {key, rows, before}
let busy = 0;
let revision = 0;

// --- HTTP ----------------------------------------------------------------------------------

function parseJSON(text) {
  // the API prints JSON as the CLI does (NaN/Infinity allowed); JSON.parse wants null
  return JSON.parse(text.replace(/([:\[,]\s*)-?(NaN|Infinity)\b/g, "$1null"));
}

async function api(method, path, body) {
  const opts = { method, headers: { "X-Kinprop-Session": SESSION } };
  if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  const r = await fetch(path, opts);
  const text = await r.text();
  let data = null;
  try { data = parseJSON(text); } catch (e) { data = { errors: [text] }; }
  return { ok: r.ok, status: r.status, data, headers: r.headers };
}

async function run(task) {
  busy += 1;
  document.body.dataset.state = "busy";
  try {
    await task();
  } catch (e) {
    showError(["internal error in the page: " + e]);
  } finally {
    busy -= 1;
    if (busy === 0) {
      revision += 1;
      document.body.dataset.revision = String(revision);
      document.body.dataset.state = "ready";
    }
  }
}

// --- formatting ----------------------------------------------------------------------------

function fmt(x, digits = 7) {
  if (x === null || x === undefined || Number.isNaN(x)) return "";
  if (x === 0) return "0";
  return String(Number(x.toPrecision(digits)));
}

function el(tag, attrs = {}, children = []) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") e.textContent = v;
    else if (k === "class") e.className = v;
    else if (v !== undefined && v !== null) e.setAttribute(k, v);
  }
  for (const c of children) e.append(c);
  return e;
}

function showError(lines) {
  const box = $("error");
  box.replaceChildren(...lines.map((l) => el("div", { text: l })));
  box.hidden = lines.length === 0;
}

function showWarnings(lines) {
  const box = $("warnings");
  box.replaceChildren(...lines.map((l) => el("div", { text: "warning: " + l })));
  box.hidden = lines.length === 0;
}

function showStatus() {
  // the status line is the server's: the change that made the current model (never a failed one)
  const s = $("status");
  s.className = "status ok";
  s.replaceChildren(el("span", { id: "status-text", text: state.status_line || "" }));
}

// --- free set ------------------------------------------------------------------------------

function freeSet() {
  const groups = [...document.querySelectorAll("#free input[type=checkbox]:checked")].map((c) => c.value);
  const extra = $("free-extra").value.split(/[\s,]+/).filter(Boolean);
  return [...groups, ...extra];
}

function weights() {
  const out = {};
  for (const w of $("weights").value.split(/\s+/).filter(Boolean)) {
    const [k, v] = w.split("=");
    out[k] = v === undefined ? w : Number(v);
  }
  return Object.keys(out).length ? out : null;
}

// --- design table --------------------------------------------------------------------------

function renderDesign() {
  const body = $("design").querySelector("tbody");
  const rows = [];
  for (const v of state.variables) {
    const tr = el("tr", { "data-address": v.address, class: v.role ? "role-" + v.role : "",
      title: v.global ? `global: [${v.global.map((x) => fmt(x, 6)).join(", ")}] ${v.unit}` : undefined });
    tr.append(el("td", { class: "addr", text: v.address }), el("td", { text: v.body }), el("td", { text: v.unit }));
    if (v.group === "C") {
      const c = v.value;  // row-major 3x3: show the joint axis z'' = third column
      const td = el("td", { colspan: 3, class: "readonly", title: "C (joint frame to body frame), rows: " +
        [0, 1, 2].map((r) => c.slice(3 * r, 3 * r + 3).map((x) => fmt(x, 5)).join(" ")).join(" | ") });
      td.textContent = "z'' = [" + [c[2], c[5], c[8]].map((x) => fmt(x, 5)).join(", ") + "]";
      tr.append(td);
    } else {
      v.value.forEach((x, k) => {
        const td = el("td");
        const inp = el("input", { type: "number", step: "any", value: fmt(x), "data-address": v.address, "data-index": k,
          "aria-label": v.value.length > 1 ? `${v.address}[${k}]` : v.address });
        inp.addEventListener("change", () => editDesign(v, k, inp));
        td.append(inp);
        if (v.before && v.before[k] !== x) td.append(el("div", { class: "before", title: "before", text: fmt(v.before[k]) }));
        tr.append(td);
      });
      for (let k = v.value.length; k < 3; k++) tr.append(el("td"));
    }
    rows.push(tr);
  }
  body.replaceChildren(...rows);
}

function renderHardpoints() {
  const body = $("hardpoints").querySelector("tbody");
  const rows = [];
  let section = null;
  for (const h of state.hardpoint_rows) {
    if (h.group !== section) {
      section = h.group;
      rows.push(el("tr", { class: "section" }, [el("th", { colspan: 5, text: section })]));
    }
    const tr = el("tr", { "data-address": h.address || "", class: state.changes.includes(h.address) ? "role-set" : "",
      title: h.address ? `${h.address} (global, ${state.units.length || ""})` : "follows the bodies (read-only)" });
    tr.append(el("td", { class: "addr", text: h.point }), el("td", { text: h.body }));
    [h.x, h.y, h.z].forEach((x, k) => {
      const td = el("td");
      if (h.address) {
        const inp = el("input", { type: "number", step: "any", value: fmt(x), "data-hardpoint": h.address, "data-index": k,
          "aria-label": `${h.address}[${"xyz"[k]}]` });
        inp.addEventListener("change", () => editHardpoint(h, k, inp));
        td.append(inp);
      } else {
        td.className = "readonly";
        td.textContent = fmt(x);
      }
      tr.append(td);
    });
    rows.push(tr);
  }
  body.replaceChildren(...rows);
  $("hardpoints").hidden = rows.length === 0;
}

function editHardpoint(h, k, inp) {
  const x = Number(inp.value);
  if (inp.value.trim() === "" || !Number.isFinite(x)) {
    showError([`${h.address}: expected a number, found ${JSON.stringify(inp.value)}`]);
    inp.value = fmt([h.x, h.y, h.z][k]);
    return;
  }
  const value = [h.x, h.y, h.z];
  value[k] = x;
  $("wrt").value = h.address;
  run(() => propagate({ [h.address]: value }, freeSet(), true, inp));
}

function editDesign(v, k, inp) {
  const x = Number(inp.value);
  if (inp.value.trim() === "" || !Number.isFinite(x)) {
    showError([`${v.address}: expected a number, found ${JSON.stringify(inp.value)}`]);
    inp.value = fmt(v.value[k]);
    return;
  }
  const value = v.value.slice();
  value[k] = x;
  $("wrt").value = v.address;  // the sensitivity table follows the variable being edited
  run(() => propagate({ [v.address]: value.length === 1 ? value[0] : value }, freeSet(), true, inp));
}

// --- propagate -----------------------------------------------------------------------------

async function propagate(set, free, design, input) {
  const body = { set, free };
  const w = weights();
  if (w) body.weights = w;
  const r = await api("POST", "/api/propagate", body);
  if (!r.ok) {
    showError(r.data.errors || [JSON.stringify(r.data)]);
    await refresh(false);
    return false;
  }
  const res = r.data;
  if (res.status !== "converged") {
    const lines = [`not applied: ${Object.keys(set).join(", ")} cannot be assembled with free ${free.join(" ")}: ${res.message}`];
    if (res.continuation) lines.push(res.continuation.message);
    showError(lines);
    await refresh(false);   // the table shows the unchanged model again
    return false;
  }
  showError([]);
  await refresh(design);
  return true;
}

// --- state ---------------------------------------------------------------------------------

async function refresh(designChanged) {
  const r = await api("GET", "/api/state");
  if (!r.ok) { showError(r.data.errors); return; }
  state = r.data;
  $("model-name").textContent = state.name;
  $("model-file").textContent = state.model;
  $("undo").disabled = state.history.undo === 0;
  $("redo").disabled = state.history.redo === 0;
  showWarnings(state.warnings || []);
  showStatus();
  renderHardpoints();
  renderDesign();
  renderSliders();
  draw3d();
  if (designChanged) await Promise.all([sweepCurve(true), sensitivity()]);
}

// --- 3D view -------------------------------------------------------------------------------

function sceneTraces(sc, faded, alpha) {
  const traces = [];
  const legend = (t) => { if (faded) { t.showlegend = traces.length === 0; t.name = "before"; } return t; };
  const opacity = faded ? alpha : 1.0;
  const tag = faded ? " (before)" : "";
  const width = { body: 6, link: 7, slide: 4, gap: 3 };
  const dash = { body: "solid", link: "solid", slide: "dash", gap: "dot" };
  for (const g of sc.segments) {
    const x = [], y = [], z = [];
    for (const [a, b] of g.lines) { x.push(a[0], b[0], null); y.push(a[1], b[1], null); z.push(a[2], b[2], null); }
    traces.push(legend({ type: "scatter3d", mode: "lines", x, y, z, opacity, hoverinfo: "name",
      name: (g.kind === "body" ? "body " + g.owner : g.kind) + tag, legendgroup: faded ? "before" : "after",
      line: { color: g.colour, width: width[g.kind] || 4, dash: faded && g.kind === "body" ? "dash" : dash[g.kind] || "solid" } }));
  }
  const byKind = {};
  for (const m of sc.markers) (byKind[m.kind] = byKind[m.kind] || []).push(m);
  for (const ms of Object.values(byKind)) {
    // labels on hover only: dense hardpoints would overlap as permanent text
    traces.push(legend({ type: "scatter3d", mode: "markers", opacity,
      x: ms.map((m) => m.at[0]), y: ms.map((m) => m.at[1]), z: ms.map((m) => m.at[2]),
      hovertext: ms.map((m) => `${m.joint} (${m.kind})`), hoverinfo: "text",
      name: ms[0].label + tag, legendgroup: faded ? "before" : "after",
      marker: { symbol: ms[0].symbol, size: 5, color: "white", line: { color: "black", width: 2 } } }));
  }
  const L = 0.12 * sc.scale;
  const axes = sc.axes;
  if (axes.length) {
    const x = [], y = [], z = [];
    for (const a of axes) {
      x.push(a.origin[0], a.origin[0] + L * a.direction[0], null);
      y.push(a.origin[1], a.origin[1] + L * a.direction[1], null);
      z.push(a.origin[2], a.origin[2] + L * a.direction[2], null);
    }
    traces.push(legend({ type: "scatter3d", mode: "lines", x, y, z, opacity, hoverinfo: "name", name: "joint axes" + tag,
      legendgroup: faded ? "before" : "after", line: { color: axes[0].colour, width: 4 } }));
  }
  const names = Object.keys(sc.points);
  if (names.length) {
    const p = names.map((n) => sc.points[n]);
    traces.push(legend({ type: "scatter3d", mode: "markers", opacity, name: "named points" + tag,
      legendgroup: faded ? "before" : "after", x: p.map((v) => v[0]), y: p.map((v) => v[1]), z: p.map((v) => v[2]),
      hovertext: names, hoverinfo: "text",
      marker: { symbol: "diamond", size: 3, color: sc.point_colour } }));
  }
  return traces;
}

// plotly camera presets (ISO 8855: x forward, y left, z up), orthographic but for "3d"
const VIEWS = {
  "3d": { eye: { x: 1.5, y: 1.5, z: 1.0 }, up: { x: 0, y: 0, z: 1 }, projection: { type: "perspective" } },
  front: { eye: { x: 1.2, y: 0, z: 0 }, up: { x: 0, y: 0, z: 1 }, projection: { type: "orthographic" } },
  side: { eye: { x: 0, y: 1.2, z: 0 }, up: { x: 0, y: 0, z: 1 }, projection: { type: "orthographic" } },
  top: { eye: { x: 0, y: 0, z: 1.2 }, up: { x: 1, y: 0, z: 0 }, projection: { type: "orthographic" } },
};
let view = "3d";

function wheelTraces(lo, hi) {
  // each wheel: the tyre as two circles (loaded radius, a drawn width of 0.4 radius) joined by
  // spokes, its spin axis; the ground plane through the lowest contact patch
  const traces = [];
  for (const w of state.wheels) {
    const c = w.centre, a = w.axis;
    const L = w.radius || 0.2 * state.scene.scale;
    traces.push({ type: "scatter3d", mode: "lines", name: `spin axis ${w.body}`, hoverinfo: "name",
      x: [c[0] - 0.5 * L * a[0], c[0] + 0.8 * L * a[0]], y: [c[1] - 0.5 * L * a[1], c[1] + 0.8 * L * a[1]],
      z: [c[2] - 0.5 * L * a[2], c[2] + 0.8 * L * a[2]], line: { color: "#333", width: 3, dash: "dashdot" } });
    if (!w.radius) continue;
    // u, v: an orthonormal basis of the wheel plane
    const t = Math.abs(a[2]) < 0.9 ? [0, 0, 1] : [1, 0, 0];
    const cross = (p, q) => [p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]];
    const norm = (p) => { const n = Math.hypot(...p); return p.map((x) => x / n); };
    const u = norm(cross(a, t)), v = cross(a, u);
    const x = [], y = [], z = [];
    for (const off of [-0.2 * w.radius, 0.2 * w.radius]) {
      for (let k = 0; k <= 48; k++) {
        const th = (2 * Math.PI * k) / 48;
        for (const [arr, i] of [[x, 0], [y, 1], [z, 2]])
          arr.push(c[i] + off * a[i] + w.radius * (Math.cos(th) * u[i] + Math.sin(th) * v[i]));
      }
      x.push(null); y.push(null); z.push(null);
    }
    traces.push({ type: "scatter3d", mode: "lines", name: `tyre ${w.body}`, hoverinfo: "name", x, y, z,
      line: { color: "#555", width: 3 } });
  }
  if (state.ground !== null && state.ground !== undefined) {
    const g = state.ground;
    traces.push({ type: "mesh3d", name: "ground plane", hoverinfo: "name", showlegend: true, opacity: 0.15, color: "#7a6a4f",
      x: [lo[0], hi[0], hi[0], lo[0]], y: [lo[1], lo[1], hi[1], hi[1]], z: [g, g, g, g], i: [0, 0], j: [1, 2], k: [2, 3] });
  }
  return traces;
}

function viewBounds() {
  // the scenes' bounds grown to hold the tyres and the ground
  const [lo0, hi0] = state.bounds;
  const lo = lo0.slice(), hi = hi0.slice();
  for (const w of state.wheels) {
    const r = w.radius || 0;
    for (let i = 0; i < 3; i++) { lo[i] = Math.min(lo[i], w.centre[i] - r); hi[i] = Math.max(hi[i], w.centre[i] + r); }
  }
  if (state.ground !== null && state.ground !== undefined) lo[2] = Math.min(lo[2], state.ground);
  return [lo, hi];
}

function draw3d() {
  const traces = [];
  const [lo, hi] = viewBounds();
  if (state.before_scene) traces.push(...sceneTraces(state.before_scene, true, state.faded_alpha));
  traces.push(...sceneTraces(state.scene, false, 1));
  traces.push(...wheelTraces(lo, hi));
  const u = state.scene.unit ? ` [${state.scene.unit}]` : "";
  const span = [0, 1, 2].map((k) => hi[k] - lo[k]);
  const big = Math.max(...span);
  const layout = {
    uirevision: view,
    margin: { l: 0, r: 0, t: 0, b: 0 },
    showlegend: true,
    legend: { font: { size: 10 }, x: 0, y: 1 },
    scene: {
      xaxis: { title: { text: "x" + u }, range: [lo[0], hi[0]] },
      yaxis: { title: { text: "y" + u }, range: [lo[1], hi[1]] },
      zaxis: { title: { text: "z" + u }, range: [lo[2], hi[2]] },
      aspectmode: "manual",
      aspectratio: { x: span[0] / big, y: span[1] / big, z: span[2] / big },
      camera: VIEWS[view],
    },
  };
  Plotly.react("view3d", traces, layout, { displaylogo: false, responsive: true });
}

function setView(name) {
  view = name;
  for (const b of document.querySelectorAll("#views button")) b.classList.toggle("active", b.dataset.view === name);
  document.body.dataset.view = name;
  draw3d();
}

// --- sliders -------------------------------------------------------------------------------

let sliderPending = null;
let sliderBusy = false;

function renderSliders() {
  const box = $("sliders");
  if (!state.sliders.length) {
    box.replaceChildren(el("div", { class: "muted", text: "no single-coordinate (revolute or translational) tree joints to drive" }));
    return;
  }
  const current = [...box.querySelectorAll("input[type=range]")].map((i) => i.dataset.address).join(" ");
  if (current === state.sliders.map((s) => s.address).join(" ")) {
    // same inputs: update the values in place (never the one being dragged), keep the ranges
    for (const s of state.sliders) {
      const inp = box.querySelector(`input[data-address="${s.address}"]`);
      if (!(inp === document.activeElement && sliderPending)) inp.value = s.value;
      inp.parentElement.querySelector(".value").textContent = `${fmt(s.value, 5)} ${s.unit}`;
    }
    return;
  }
  const rows = state.sliders.map((s) => {
    const step = (s.slider[1] - s.slider[0]) / 400;
    const inp = el("input", { type: "range", min: s.slider[0], max: s.slider[1], step, value: s.value, "data-address": s.address, "aria-label": s.address });
    const out = el("span", { class: "value", text: `${fmt(s.value, 5)} ${s.unit}` });
    inp.addEventListener("input", () => {
      out.textContent = `${fmt(Number(inp.value), 5)} ${s.unit}`;
      sliderPending = { address: s.address, value: Number(inp.value) };
      pumpSlider();
    });
    return el("div", { class: "slider" }, [el("label", { text: `${s.address} (${s.type})` }), inp, out]);
  });
  box.replaceChildren(...rows);
}

function pumpSlider() {
  if (sliderBusy || !sliderPending) return;
  const { address, value } = sliderPending;
  sliderPending = null;
  sliderBusy = true;
  // the input's coordinate is set; the other coordinates follow (free: q)
  run(() => propagate({ [address]: value }, ["q"], false)).finally(() => { sliderBusy = false; pumpSlider(); });
}

// --- curves --------------------------------------------------------------------------------

function renderCurveControls() {
  const drive = $("drive");
  drive.replaceChildren(...state.drives.map((d) => el("option", { value: d.spec, text: `${d.address} [${d.unit}]` })));
  const outs = $("outputs");
  outs.replaceChildren(...state.outputs.map((o) => el("option", { value: o, text: o })));
  for (const opt of outs.options) opt.selected = state.default_outputs.includes(opt.value);
  drive.addEventListener("change", setDriveRange);
  setDriveRange();
  const wrt = state.variables.find((v) => v.group === "s");
  $("wrt").value = wrt ? wrt.address : "";
}

function setDriveRange() {
  const d = state.drives.find((x) => x.spec === $("drive").value);
  if (!d) return;
  $("drive-from").value = fmt(d.curve[0], 5);
  $("drive-to").value = fmt(d.curve[1], 5);
}

function curveRequest() {
  const spec = $("drive").value;
  if (!spec) return null;
  const outs = [...$("outputs").selectedOptions].map((o) => o.value);
  return { drive: [`${spec}=${$("drive-from").value}:${$("drive-to").value}:${$("drive-steps").value}`], out: outs, free: ["q"] };
}

async function sweepCurve(designChanged) {
  const req = curveRequest();
  if (!req) return;
  const key = JSON.stringify(req);
  const t0 = performance.now();
  const r = await api("POST", "/api/sweep", req);
  if (!r.ok) { $("curve-status").textContent = "sweep: " + (r.data.errors || []).join("; "); return; }
  const before = curve && curve.key === key && designChanged ? curve.rows : null;
  // outputs naming a coordinate are the sweep's coordinate columns (model units)
  const outputs = req.out.length ? req.out.filter((o) => o in r.data.rows[0] || r.data.outputs.includes(o)) : r.data.outputs;
  curve = { key, rows: r.data.rows, before, drive: r.data.drives[0], outputs: [...new Set([...outputs, ...r.data.outputs])] };
  const failed = r.data.failed.length;
  $("curve-status").textContent = `${r.data.steps} steps, ${r.data.converged} converged` +
    (failed ? `, ${failed} failed (first: ${r.data.rows[r.data.failed[0]].message})` : "") +
    `; ${Math.round(performance.now() - t0)} ms`;
  drawCurves();
}

function drawCurves() {
  const { rows, before, drive, outputs } = curve;
  const traces = [];
  const palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b"];
  outputs.forEach((o, k) => {
    const c = palette[k % palette.length];
    const yaxis = k === 0 ? "y" : "y2";
    if (before) traces.push({ x: before.map((r) => r[drive]), y: before.map((r) => r[o]), name: o + " (before)", yaxis,
      mode: "lines", line: { color: c, dash: "dash", width: 1.5 }, opacity: 0.5 });
    traces.push({ x: rows.map((r) => r[drive]), y: rows.map((r) => r[o]), name: o, yaxis, mode: "lines+markers",
      marker: { size: 3 }, line: { color: c, width: 2 } });
  });
  const layout = {
    margin: { l: 60, r: 60, t: 10, b: 40 }, height: 260,
    xaxis: { title: { text: drive } },
    yaxis: { title: { text: outputs[0] || "" } },
    yaxis2: { title: { text: outputs[1] || "" }, overlaying: "y", side: "right" },
    legend: { orientation: "h", y: -0.25, font: { size: 10 } },
  };
  Plotly.react("curves", traces, layout, { displaylogo: false, responsive: true });
}

// --- sensitivity ---------------------------------------------------------------------------

async function sensitivity() {
  const wrt = $("wrt").value.split(/[\s,]+/).filter(Boolean);
  if (!wrt.length) return;
  const of = [...$("outputs").selectedOptions].map((o) => o.value);
  const body = { wrt, free: freeSet() };
  if (of.length) body.of = of;
  const w = weights();
  if (w) body.weights = w;
  const r = await api("POST", "/api/sensitivity", body);
  const table = $("sensitivity");
  if (!r.ok) {
    table.replaceChildren(el("caption", { class: "failed", text: (r.data.errors || []).join("; ") }));
    return;
  }
  const d = r.data;
  const head = el("tr", {}, [el("th", { text: "d(output) / d(design)" }), ...d.wrt.map((c) => el("th", { text: c }))]);
  const rows = d.of.map((o, i) => el("tr", {}, [el("th", { text: o }), ...d.matrix[i].map((x) => el("td", { text: fmt(x, 5) }))]));
  table.replaceChildren(el("thead", {}, [head]), el("tbody", {}, rows));
}

// --- history -------------------------------------------------------------------------------

async function history(what) {
  const r = await api("POST", "/api/" + what);
  if (!r.ok) { showError(r.data.errors); return; }
  showError([]);
  await refresh(true);
}

function downloads() {
  for (const id of ["dl-model", "dl-csv", "dl-json", "dl-report"]) {
    const a = $(id);
    a.href = a.getAttribute("href").split("?")[0] + "?session=" + encodeURIComponent(SESSION);
  }
}

// --- start ---------------------------------------------------------------------------------

window.addEventListener("DOMContentLoaded", () => {
  downloads();
  for (const b of document.querySelectorAll("#views button")) b.addEventListener("click", () => setView(b.dataset.view));
  $("undo").addEventListener("click", () => run(() => history("undo")));
  $("redo").addEventListener("click", () => run(() => history("redo")));
  $("reset").addEventListener("click", () => run(() => history("reset")));
  $("curve-go").addEventListener("click", () => run(() => sweepCurve(false)));
  $("sens-go").addEventListener("click", () => run(sensitivity));
  $("wrt").addEventListener("change", () => run(sensitivity));
  $("outputs").addEventListener("change", () => run(() => Promise.all([sweepCurve(false), sensitivity()])));
  document.addEventListener("keydown", (e) => {
    if (!(e.ctrlKey || e.metaKey) || e.target.tagName === "INPUT") return;
    if (e.key === "z") { e.preventDefault(); run(() => history("undo")); }
    if (e.key === "y") { e.preventDefault(); run(() => history("redo")); }
  });
  run(async () => {
    await refresh(false);
    $("body-frames").open = !state.hardpoint_style;  // a hardpoint file is edited by its hardpoints
    renderCurveControls();
    await Promise.all([sweepCurve(false), sensitivity()]);
  });
});

// The results overlay of the Live view: the latest VisionResult of the
// selected app drawn over the frame (outlines, labels, pose axes, grasp,
// fingers, rejected regions), and its summary in the Live panel. Sets
// picksight.lastOverlay to what it drew, in CSS pixels of the image.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const num = (v) => Number(v || 0);  // proto JSON omits zeros, and writes 64-bit ints as strings
  const pt = (p) => [num(p && p.x), num(p && p.y)];

  function polygonPath(m, polygons) {
    let d = "";
    for (const poly of polygons || []) {
      const points = (poly && poly.points) || [];
      points.forEach((p, i) => {
        const f = ps.sensorToFrame(m, num(p.x), num(p.y));
        d += (i ? "L" : "M") + f[0].toFixed(2) + " " + f[1].toFixed(2);
      });
      if (points.length) d += "Z";
    }
    return d;
  }

  // Where a part's reply pose is drawn: the chosen grasp, else the part itself.
  function graspPoint(part) {
    return part.grasp_position ? pt(part.grasp_position) : pt(part.position);
  }

  function drawPart(g, m, result, part, index, size, drawn) {
    const svg = ps.svg;
    const cls = part.offered ? "part" : "part not-offered";
    const group = svg(g, "g", { class: cls, "data-index": index });
    // A part without a model (type -1) has its region's outline.
    const region = (result.regions || []).find((r) => num(r.index) === num(part.region));
    const outline = part.outline && part.outline.length ? part.outline : region ? [region.outline] : [];
    if (outline.length) {
      svg(group, "path", { class: "outline", d: polygonPath(m, outline), "fill-rule": "evenodd" });
    }
    for (const finger of part.fingers || []) {
      svg(group, "path", {
        class: finger.blocked ? "finger blocked" : "finger free",
        d: polygonPath(m, [finger.footprint]),
      });
    }
    const [sx, sy] = pt(part.position);
    const c = ps.sensorToFrame(m, sx, sy);
    // Pose axes: x along the part's rotation (image axes, clockwise), y at +90.
    const a = num(part.angle_deg) * Math.PI / 180;
    const len = size * 0.06;
    svg(group, "line", { class: "axis-x", x1: c[0], y1: c[1], x2: c[0] + len * Math.cos(a), y2: c[1] + len * Math.sin(a) });
    svg(group, "line", { class: "axis-y", x1: c[0], y1: c[1], x2: c[0] - len * Math.sin(a), y2: c[1] + len * Math.cos(a) });
    const [gx, gy] = graspPoint(part);
    const gf = ps.sensorToFrame(m, gx, gy);
    const ga = num(part.grasp_position ? part.grasp_angle_deg : part.angle_deg) * Math.PI / 180;
    const r = size * 0.012;
    svg(group, "circle", { class: "grasp", cx: gf[0], cy: gf[1], r: r, "data-sensor-x": gx, "data-sensor-y": gy });
    svg(group, "line", { class: "grasp-dir", x1: gf[0], y1: gf[1], x2: gf[0] + 3 * r * Math.cos(ga), y2: gf[1] + 3 * r * Math.sin(ga) });
    const type = num(part.type);
    const label = (type >= 0 ? (part.name || "type" + type) + " #" + type : "region") +
                  (part.score ? " " + num(part.score).toFixed(2) : "") + (part.touching ? " touching" : "");
    // Labels near the right edge go to the left of the part, inside the frame.
    const right = c[0] > 0.7 * m.frameW;
    svg(group, "text", { class: "label", x: c[0] + (right ? -2 * r : 2 * r), y: c[1] - r * 2,
                         "font-size": size * 0.025, "text-anchor": right ? "end" : "start" }, label);
    const d = ps.frameToDisplay(m, gf[0], gf[1]);
    drawn.parts.push({
      index, type, name: part.name || "", score: num(part.score), offered: !!part.offered,
      sensor_x: gx, sensor_y: gy, x: d[0], y: d[1],
      part_x: sx, part_y: sy, fingers: (part.fingers || []).map((f) => !!f.blocked),
    });
  }

  function drawRejection(g, m, result, rej, size, drawn) {
    const region = (result.regions || []).find((r) => num(r.index) === num(rej.region));
    if (!region) return;
    const group = ps.svg(g, "g", { class: "rejection", "data-region": num(rej.region) });
    ps.svg(group, "path", { class: "rejected", d: polygonPath(m, [region.outline]) });
    const f = ps.sensorToFrame(m, num(region.box_x) + num(region.box_width), num(region.box_y));
    ps.svg(group, "text", { class: "reason", x: f[0] + 4, y: f[1] + size * 0.025, "font-size": size * 0.022 },
           rej.text || rej.test || "rejected");
    const c = pt(region.centroid);
    drawn.rejections.push({ region: num(rej.region), test: rej.test || "", text: rej.text || "", sensor_x: c[0], sensor_y: c[1] });
  }

  function draw() {
    const svgRoot = $("overlay");
    svgRoot.textContent = "";
    ps.sizeLayers();
    const result = ps.app ? ps.latest[ps.app] : null;
    const drawn = { app: ps.app, request_id: null, parts: [], rejections: [], regions: 0 };
    ps.lastOverlay = drawn;
    svgRoot.dataset.parts = "0";
    if (!result || !$("live-overlay").checked) return;
    if (result.camera && ps.camera && result.camera !== ps.camera) return;
    const m = ps.mapping();
    const size = Math.max(m.frameW, m.frameH);
    drawn.request_id = String(result.request_id || "0");
    const g = ps.svg(svgRoot, "g", { "stroke-width": Math.max(1, size / 400) });
    if ($("live-regions").checked) {
      for (const region of result.regions || []) {
        ps.svg(g, "path", { class: "region", d: polygonPath(m, [region.outline]) });
        drawn.regions += 1;
      }
    }
    for (const rej of result.rejections || []) drawRejection(g, m, result, rej, size, drawn);
    (result.parts || []).forEach((part, i) => drawPart(g, m, result, part, i, size, drawn));
    svgRoot.dataset.parts = String(drawn.parts.length);
    svgRoot.dataset.requestId = drawn.request_id;
  }
  ps.drawOverlay = draw;

  function summarize() {
    const result = ps.app ? ps.latest[ps.app] : null;
    const tbody = $("result-parts").querySelector("tbody");
    tbody.textContent = "";
    $("result-rejections").textContent = "";
    if (!result) { $("result-summary").textContent = "no result yet"; return; }
    $("result-summary").textContent =
      "#" + (result.request_id || 0) + " " + (result.request_line || result.request || "") + " -> " +
      (result.reply || "") + " (" + num(result.elapsed_ms).toFixed(1) + " ms, frame " +
      (result.frame_sequence || 0) + ", " + num(result.regions_total) + " regions)" +
      (result.why ? "\nwhy: " + result.why : "");
    for (const part of result.parts || []) {
      const [x, y] = pt(part.position);
      const fingers = (part.fingers || []).map((f) => (f.blocked ? "blocked" : "free")).join(" ");
      const row = ps.tableRow(tbody, [
        num(part.type), part.name || "", num(part.score).toFixed(3), x.toFixed(1), y.toFixed(1),
        num(part.angle_deg).toFixed(1),
        (part.offered ? "style " + num(part.grasp_style) : "not offered") + (fingers ? " (" + fingers + ")" : ""),
      ]);
      if (!part.offered) row.className = "not-offered";
    }
    for (const rej of result.rejections || []) {
      const li = document.createElement("li");
      li.textContent = "region " + num(rej.region) + ": " + (rej.text || rej.test);
      $("result-rejections").appendChild(li);
    }
  }

  function refresh() { draw(); summarize(); }

  // Live panel buttons: protocol lines to the selected app.
  async function say(line) {
    const reply = await ps.command(line);
    ps.show("live-reply", line, reply);
    return reply;
  }

  document.addEventListener("DOMContentLoaded", () => {
    ps.on("result", (r) => { if (r.app === ps.app) refresh(); });
    ps.on("camera", refresh);
    ps.on("cameras", draw);
    ps.on("frame", draw);
    $("frame").addEventListener("load", draw);
    for (const id of ["live-overlay", "live-regions"]) $(id).addEventListener("change", draw);
    $("live-binary").addEventListener("change", (e) => { ps.binaryWanted = e.target.checked; ps.showFrame(); });
    $("live-locate").addEventListener("click", () => say("LOCATE " + ($("live-type").value.trim() || "ALL")));
    // WHY answers about the last LOCATE on the same connection: a LOCATE
    // from elsewhere (a robot) is explained by the latest result's text.
    $("live-why").addEventListener("click", async () => {
      const reply = await say("WHY");
      const result = ps.app ? ps.latest[ps.app] : null;
      if (reply.includes("no LOCATE yet") && result && result.why) {
        ps.show("live-reply", "(latest result #" + (result.request_id || 0) + ")", result.why);
      }
    });
    $("live-status").addEventListener("click", () => say("STATUS"));
  });
})();

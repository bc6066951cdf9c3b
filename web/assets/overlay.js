// The results overlay of the Live view: the latest VisionResult of the
// selected app drawn over the frame (outlines, labels, pose axes, grasp,
// fingers, rejected regions with the remedy WHY names), and its summary in
// the Live panel. Regions unlike any part (belt texture, shadows: the
// rejection's unlike_any_part) are outlined faintly without a label unless
// "all reasons" is ticked, so the near misses' labels stand out. Labels are
// placed so that none covers another, and a label under the mouse is
// highlighted with its region. Sets picksight.lastOverlay to what it drew,
// in CSS pixels of the image.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const num = (v) => Number(v || 0);  // proto JSON omits zeros, and writes 64-bit ints as strings
  const pt = (p) => [num(p && p.x), num(p && p.y)];
  const unlike = (rej) => !!rej.unlike_any_part;

  // The rejections near misses first, each group in region order (as the
  // result lists them): their labels take the first spots.
  function nearMissesFirst(rejections) {
    return (rejections || []).filter((r) => !unlike(r)).concat((rejections || []).filter(unlike));
  }

  // "31 regions unlike any part".
  function unlikeCount(n) { return n + (n === 1 ? " region" : " regions") + " unlike any part"; }

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

  function drawPart(g, m, result, part, index, size, drawn, labels) {
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
    const text = svg(group, "text", { class: "label", x: 0, y: 0, "font-size": size * 0.025 }, label);
    labels.push({ el: text, x: c[0], y: c[1], gap: 2 * r });
    const d = ps.frameToDisplay(m, gf[0], gf[1]);
    drawn.parts.push({
      index, type, name: part.name || "", score: num(part.score), offered: !!part.offered,
      sensor_x: gx, sensor_y: gy, x: d[0], y: d[1],
      part_x: sx, part_y: sy, fingers: (part.fingers || []).map((f) => !!f.blocked),
    });
  }

  function drawRejection(g, m, result, rej, size, drawn, labels, allReasons) {
    const region = (result.regions || []).find((r) => num(r.index) === num(rej.region));
    if (!region) return;
    const cls = unlike(rej) ? "rejection unlike" : "rejection";
    const group = ps.svg(g, "g", { class: cls, "data-region": num(rej.region) });
    ps.svg(group, "path", { class: "rejected", d: polygonPath(m, [region.outline]) });
    const c = pt(region.centroid);
    const seen = { region: num(rej.region), test: rej.test || "", text: rej.text || "",
                   remedy: rej.remedy_key ? rej.remedy_key + " " + rej.remedy_value : "",
                   unlike: unlike(rej), labelled: !unlike(rej) || allReasons,
                   sensor_x: c[0], sensor_y: c[1] };
    drawn.rejections.push(seen);
    if (!seen.labelled) {
      drawn.unlabelled += 1;
      return;
    }
    const f = ps.sensorToFrame(m, num(region.box_x) + num(region.box_width), num(region.box_y));
    // The reason on one line; the remedy, when WHY names one, on a second
    // that applies it when clicked.
    const reason = rej.text || rej.test || "rejected";
    const cut = rej.remedy_key ? reason.indexOf(", " + rej.remedy_key + " ") : -1;
    const text = ps.svg(group, "text", { class: "reason", x: 0, y: 0, "font-size": size * 0.022 });
    ps.svg(text, "tspan", {}, cut >= 0 ? reason.slice(0, cut) : reason);
    if (rej.remedy_key) {
      const remedy = ps.svg(text, "tspan", { class: "remedy", x: 0, dy: "1.2em", "data-region": num(rej.region) },
                            "apply " + rej.remedy_key + " " + rej.remedy_value);
      remedy.addEventListener("click", () => applyRemedy(result, rej));
    }
    labels.push({ el: text, x: f[0], y: f[1], gap: size * 0.006 });
  }

  // The labels placed one after another (parts first, then the reasons),
  // each at the first of a few spots around its anchor, nearest first,
  // where it stays inside the frame and covers no label placed before it;
  // with no such spot, the first inside the frame. Boxes are the text's
  // own (getBBox, frame pixels).
  function placeLabels(labels, m) {
    const placed = [];
    const overlaps = (a, b) => a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
    for (const l of labels) {
      const box = l.el.getBBox();
      const w = box.width;
      const h = box.height;
      const spots = [];
      for (let k = 0; k < 8; k++) {
        const d = l.gap + k * h;
        spots.push([l.x + l.gap, l.y - d - h], [l.x + l.gap, l.y + d], [l.x - l.gap - w, l.y - d - h],
                   [l.x - l.gap - w, l.y + d], [l.x - w / 2, l.y - d - 2 * h], [l.x - w / 2, l.y + d + h]);
      }
      const boxAt = (s) => ({ x: s[0], y: s[1], w, h });
      const inside = (s) => s[0] >= 0 && s[1] >= 0 && s[0] + w <= m.frameW && s[1] + h <= m.frameH;
      const spot = spots.find((s) => inside(s) && !placed.some((p) => overlaps(boxAt(s), p))) ||
                   spots.find(inside) || spots[0];
      // The text's origin is its first baseline: moved by the box's offset.
      const x = spot[0] - box.x;
      l.el.setAttribute("x", x);
      l.el.setAttribute("y", spot[1] - box.y);
      for (const line of l.el.querySelectorAll("tspan[dy]")) line.setAttribute("x", x);
      placed.push(boxAt(spot));
    }
  }

  // TOLERANCE as WHY named it for the rejected region, then the result's
  // own LOCATE again, which the remedy was checked with: the region should
  // now be a part.
  async function applyRemedy(result, rej) {
    const line = "TOLERANCE " + num(rej.nearest_type) + " " + rej.remedy_key + " " + rej.remedy_value;
    const reply = await say(line);
    const request = String(result.request_line || "");
    if (reply.startsWith("OK") && request.toUpperCase().startsWith("LOCATE")) await say(request);
  }

  function draw() {
    const svgRoot = $("overlay");
    svgRoot.textContent = "";
    ps.sizeLayers();
    const result = ps.app ? ps.latest[ps.app] : null;
    const drawn = { app: ps.app, request_id: null, parts: [], rejections: [], regions: 0, labels: 0,
                    unlabelled: 0 };
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
    const partLabels = [];
    const reasons = [];
    const allReasons = $("live-all-reasons").checked;
    for (const rej of nearMissesFirst(result.rejections)) {
      drawRejection(g, m, result, rej, size, drawn, reasons, allReasons);
    }
    (result.parts || []).forEach((part, i) => drawPart(g, m, result, part, i, size, drawn, partLabels));
    // Parts' labels first: they are placed nearest their parts.
    placeLabels(partLabels.concat(reasons), m);
    drawn.labels = partLabels.length + reasons.length;
    svgRoot.dataset.parts = String(drawn.parts.length);
    svgRoot.dataset.requestId = drawn.request_id;
  }
  ps.drawOverlay = draw;

  let unlikeOpen = false;  // the Live list's line of regions unlike any part

  function summarize() {
    const result = ps.app ? ps.latest[ps.app] : null;
    const tbody = $("result-parts").querySelector("tbody");
    tbody.textContent = "";
    $("result-rejections").textContent = "";
    if (!result) {
      $("result-summary").textContent = "no result yet";
      $("result-frame").textContent = "the reply's frame";
      return;
    }
    $("result-summary").textContent =
      "#" + (result.request_id || 0) + " " + (result.request_line || result.request || "") + " -> " +
      (result.reply || "") + " (" + num(result.elapsed_ms).toFixed(1) + " ms, frame " +
      (result.frame_sequence || 0) + ", " + num(result.regions_total) + " regions)" +
      // WHY's line where no rejection is listed below (a failed LOCATE, or
      // every region reported): the list says it region by region, near
      // misses first, and WHY's line of a belt ran to its 1000 bytes.
      (result.why && !(result.rejections || []).length ? "\nwhy: " + result.why : "") +
      unlikeNote(result) +
      (result.reply_frame ? "\nreply in " + ps.replyFrame(result.reply_frame).text : "");
    const frame = ps.replyFrame(result.reply_frame);
    $("result-frame").textContent = frame.text;
    $("result-frame").dataset.frame = result.reply_frame || "";
    $("result-frame").title = frame.title;
    for (const unit of document.querySelectorAll("#result-parts th .unit")) unit.textContent = frame.short;
    $("result-parts").querySelector("th[data-col=reply]").title = frame.title;
    for (const part of result.parts || []) {
      const [x, y] = pt(part.position);
      const modelled = num(part.type) >= 0;
      const fingers = (part.fingers || []).map((f) => (f.blocked ? "blocked" : "free")).join(" ");
      const style = num(part.grasp_style);
      // A region with no model has no score and no grasp style: it is
      // reported at its own pose.
      const grasp = !part.offered ? "not offered" : style >= 0 ? "style " + (style + 1) : "own pose";
      const pose = part.offered ? part.reply_pose || {} : null;
      const row = ps.tableRow(tbody, [
        num(part.type) + " " + (modelled ? part.name || "" : "no model"), modelled ? num(part.score).toFixed(2) : "-",
        x.toFixed(1), y.toFixed(1), num(part.angle_deg).toFixed(1), grasp,
        pose ? num(pose.x).toFixed(1) : "-", pose ? num(pose.y).toFixed(1) : "-", pose ? num(pose.rz_deg).toFixed(1) : "-",
      ]);
      // The fingers' states in the grasp cell's tooltip: the column stays narrow.
      if (fingers) row.cells[5].title = "fingers: " + fingers;
      if (!part.offered) row.className = "not-offered";
      if (!modelled) row.classList.add("no-model");
    }
    // Near misses one a line; the regions unlike any part in one line that
    // opens to list them.
    const near = (result.rejections || []).filter((r) => !unlike(r));
    const rest = (result.rejections || []).filter(unlike);
    for (const rej of near) $("result-rejections").appendChild(rejectionItem(result, rej));
    if (rest.length) {
      const li = document.createElement("li");
      li.className = "unlike";
      const details = document.createElement("details");
      // Open stays open as results arrive (the list is built anew each time).
      details.open = unlikeOpen;
      details.addEventListener("toggle", () => { unlikeOpen = details.open; });
      const head = document.createElement("summary");
      head.textContent = unlikeCount(rest.length) + " (far from every part in area or shape)";
      const list = document.createElement("ul");
      for (const rej of rest) list.appendChild(rejectionItem(result, rej));
      details.append(head, list);
      li.appendChild(details);
      $("result-rejections").appendChild(li);
    }
  }

  // The summary's line on the regions unlike any part: how many the
  // overlay leaves unlabelled, or that "all reasons" labels them.
  function unlikeNote(result) {
    const n = (result.rejections || []).filter(unlike).length;
    if (!n) return "";
    return "\n" + unlikeCount(n) + ($("live-all-reasons").checked
      ? ", labelled (all reasons)" : " left unlabelled, outlined faintly (all reasons labels them)");
  }

  function rejectionItem(result, rej) {
    const li = document.createElement("li");
    // WHY's sentence names its region; a bare test name does not.
    li.textContent = rej.text || "region " + num(rej.region) + ": " + rej.test;
    if (rej.remedy_key) {
      const apply = document.createElement("button");
      apply.type = "button";
      apply.className = "remedy";
      apply.dataset.region = String(num(rej.region));
      apply.textContent = "apply " + rej.remedy_key + " " + rej.remedy_value;
      apply.title = "TOLERANCE " + num(rej.nearest_type) + " " + rej.remedy_key + " " + rej.remedy_value +
                    ", then " + (result.request_line || "LOCATE");
      apply.addEventListener("click", () => applyRemedy(result, rej));
      li.append(" ", apply);
    }
    return li;
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
    // The summary says whether the regions unlike any part are labelled.
    $("live-all-reasons").addEventListener("change", refresh);
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

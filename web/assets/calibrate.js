// The Calibrate panel: CALCAM, STORE, LIST, DELETE, COMPUTE (each method),
// RESIDUALS and CLEARCAL as protocol lines; the stored points and their
// residual arrows drawn on the image; and, with a synthetic camera, the
// whole calibration run by its simulated robot. A refusal (CALCAM without a
// target, a target moved off the image) stays on top of the panel in red
// until the next button is pressed: the refreshes that follow (STATUS, LIST)
// would scroll it out of the reply log.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  // Residuals are hundredths of a mm: the largest is drawn this long.
  const LONGEST_ARROW_PX = 40;
  const cal = { points: [], residuals: {}, mmPerPx: [1, 1], rz: 0, pxPerMm: 1 };

  // The panel's last refusal, on top; cleared when a button is pressed.
  function showError(line, reply) {
    if (!reply.startsWith("ERROR")) return;
    $("cal-error").textContent = line + ": " + reply;
    $("cal-error").hidden = false;
  }

  async function say(line) {
    const reply = await ps.command(line);
    ps.show("cal-reply", line, reply);
    showError(line, reply);
    return reply;
  }

  // STATUS's key=value fields.
  async function status() {
    const f = ps.okFields(await say("STATUS")) || [];
    const kv = {};
    for (const w of f) {
      const i = w.indexOf("=");
      if (i > 0) kv[w.slice(0, i)] = w.slice(i + 1);
    }
    const mm = kv.scale && kv.scale !== "none" ? kv.scale.split("x").map(Number) : [];
    const scaled = mm.length === 2 && mm[0] > 0 && mm[1] > 0;
    cal.mmPerPx = scaled ? mm : [1, 1];
    // LIST's vision coordinates are sensor pixels until CALCAM gives a scale.
    const unit = scaled ? "mm" : "px";
    for (const el of document.querySelectorAll("#cal-points th .unit")) el.textContent = unit;
    $("cal-vision-unit").textContent = scaled ? "mm" : "sensor px (no CALCAM yet)";
    const t = kv.transform && kv.transform !== "none" ? kv.transform.split(",").map(Number) : null;
    cal.rz = t ? t[2] : 0;
    $("cal-transform").textContent =
      "frame " + (kv.frame || "?") + ", scale " + (scaled ? kv.scale + " mm/px" : (kv.scale || "?") + " (1 unit per px)") +
      ", points " + (kv.points || 0) +
      ", transform " + (t ? "dx " + t[0] + " mm, dy " + t[1] + " mm, rz " + t[2] + "\u00b0, rms " + kv.rms + " mm" : "none") +
      (kv.calibration === "damaged" ? " (calibration file damaged)" : "");
    return kv;
  }

  async function refreshPoints() {
    await status();
    const f = ps.okFields(await say("LIST")) || ["0"];
    const n = Number(f[0]) || 0;
    cal.points = [];
    for (let i = 0; i < n; ++i) cal.points.push(f.slice(1 + 5 * i, 6 + 5 * i).map(Number));
    cal.residuals = {};
    const r = ps.okFields(await ps.command("RESIDUALS"));
    if (r) {
      const m = Number(r[0]) || 0;
      for (let i = 0; i < m; ++i) {
        const [id, dx, dy, dist] = r.slice(1 + 4 * i, 5 + 4 * i).map(Number);
        cal.residuals[id] = { dx, dy, dist };
      }
    }
    const largest = Math.max(0, ...Object.values(cal.residuals).map((r) => r.dist));
    cal.pxPerMm = largest > 0 ? LONGEST_ARROW_PX / largest : 1;
    $("cal-arrow-gain").textContent = cal.pxPerMm >= 10 ? cal.pxPerMm.toFixed(0) : cal.pxPerMm.toPrecision(2);
    const tbody = $("cal-points").querySelector("tbody");
    tbody.textContent = "";
    for (const p of cal.points) {
      const res = cal.residuals[p[0]];
      ps.tableRow(tbody, [p[0], p[1], p[2], p[3], p[4], res ? res.dist.toFixed(3) : "-"], "Delete", async () => {
        await say("DELETE " + p[0]);
        refreshPoints();
      });
    }
    ps.drawTool();
  }

  // Stored points (vision mm: y up) at their sensor pixels, and each
  // residual (robot mm) turned back into the vision frame as an arrow.
  function drawPoints(tool, m) {
    if (ps.tab !== "calibrate") return;
    const [mmx, mmy] = cal.mmPerPx;
    const back = -cal.rz * Math.PI / 180;
    for (const p of cal.points) {
      const c = ps.sensorToFrame(m, p[1] / mmx, -p[2] / mmy);
      const g = ps.svg(tool, "g", { class: "cal-point", "data-id": p[0] });
      ps.svg(g, "circle", { cx: c[0], cy: c[1], r: 4 });
      ps.svg(g, "text", { x: c[0] + 6, y: c[1] - 6 }, String(p[0]));
      const res = cal.residuals[p[0]];
      if (!res) continue;
      const vx = res.dx * Math.cos(back) - res.dy * Math.sin(back);
      const vy = res.dx * Math.sin(back) + res.dy * Math.cos(back);
      const ex = c[0] + vx * cal.pxPerMm * m.scaleX, ey = c[1] - vy * cal.pxPerMm * m.scaleY;
      ps.svg(g, "line", { class: "residual", x1: c[0], y1: c[1], x2: ex, y2: ey });
      ps.svg(g, "circle", { class: "residual-tip", cx: ex, cy: ey, r: 2 });
    }
  }

  async function moveTarget(body) {
    const r = await ps.cameraAction("target", body);
    const line = body.hide ? "hide target" : "move target to robot " + body.x_mm + " " + body.y_mm + " mm";
    const reply = r.ok ? "OK" : "ERROR " + r.body.error;
    ps.show("cal-reply", line, reply);
    showError(line, reply);
    return r;
  }

  // The simulated robot's state wherever the server put it in its reply.
  function findRobot(obj, depth) {
    if (!obj || typeof obj !== "object" || depth > 4) return null;
    if (Array.isArray(obj.robot_to_sensor) && obj.robot_to_sensor.length === 9) return obj;
    for (const k in obj) {
      const found = findRobot(obj[k], depth + 1);
      if (found) return found;
    }
    return null;
  }

  // Sensor pixel -> robot mm through the inverse of the hidden homography.
  function sensorToRobot(h, u, v) {
    const [a, b, c, d, e, f, g, hh, i] = h.map(Number);
    const inv = [e * i - f * hh, c * hh - b * i, b * f - c * e,
                 f * g - d * i, a * i - c * g, c * d - a * f,
                 d * hh - e * g, b * g - a * hh, a * e - b * d];
    const w = inv[6] * u + inv[7] * v + inv[8];
    return [(inv[0] * u + inv[1] * v + inv[2]) / w, (inv[3] * u + inv[4] * v + inv[5]) / w];
  }

  // The whole calibration on a synthetic camera: an empty table, the disc in
  // the middle for CALCAM, then N points over the view, COMPUTE.
  async function simulate() {
    const button = $("cal-simulate");
    button.disabled = true;
    try {
      const hidden = await moveTarget({ hide: true });
      const robot = hidden.ok ? findRobot(hidden.body, 0) : null;
      if (!robot) {
        ps.show("cal-reply", "simulated robot", "ERROR the camera has no simulated robot (a synthetic camera has one)");
        return;
      }
      await ps.cameraAction("feature", { name: "Parts", value: "0" });
      const m = ps.mapping();
      const w = m.sensorW, h = m.sensorH;
      const radius = Number(robot.target_radius_mm) || Number($("cal-radius").value) || 5;
      ps.setField("cal-radius", radius, true);
      await say("CLEARCAL");
      const centre = sensorToRobot(robot.robot_to_sensor, 0.5 * (w - 1), 0.5 * (h - 1));
      await moveTarget({ x_mm: centre[0], y_mm: centre[1] });
      if (!(await say("CALCAM " + radius)).startsWith("OK")) return;
      const n = Math.min(64, Math.max(3, Math.round(Number($("cal-sim-points").value) || 8)));
      const cols = Math.ceil(n / 2);
      for (let i = 0; i < n; ++i) {
        // Two staggered rows inside the central 80 % of the view.
        const fx = cols > 1 ? 0.1 + 0.8 * (i % cols) / (cols - 1) : 0.5;
        const fy = i < cols ? 0.15 + 0.05 * (i % 2) : 0.8 + 0.05 * (i % 2);
        const r = sensorToRobot(robot.robot_to_sensor, fx * (w - 1), fy * (h - 1));
        const x = r[0].toFixed(3), y = r[1].toFixed(3);
        ps.setField("cal-robot-x", x, true);  // the point being stored
        ps.setField("cal-robot-y", y, true);
        await moveTarget({ x_mm: Number(x), y_mm: Number(y) });
        await say("STORE " + x + " " + y);
      }
      await say("COMPUTE " + $("cal-method").value);
      await moveTarget({ hide: true });
      await refreshPoints();
    } finally {
      button.disabled = false;
    }
  }

  const val = (id) => Number($(id).value) || 0;

  document.addEventListener("DOMContentLoaded", () => {
    // Each press starts with no refusal shown (capture: before its handler).
    $("panel-calibrate").addEventListener("click", (e) => {
      if (e.target.tagName === "BUTTON") {
        $("cal-error").textContent = "";
        $("cal-error").hidden = true;
      }
    }, true);
    ps.toolDrawers.push(drawPoints);
    ps.on("tab", (tab) => { if (tab === "calibrate") refreshPoints(); });
    $("cal-status").addEventListener("click", status);
    const robotFields = ["cal-robot-x", "cal-robot-y"];
    $("cal-calcam").addEventListener("click", async () => {
      await ps.applyFields(["cal-radius"], () => say("CALCAM " + val("cal-radius")));
      status();
    });
    $("cal-move").addEventListener("click", () =>
      ps.applyFields(robotFields, () => moveTarget({ x_mm: val("cal-robot-x"), y_mm: val("cal-robot-y") })));
    $("cal-hide").addEventListener("click", () => moveTarget({ hide: true }));
    $("cal-store").addEventListener("click", async () => {
      await ps.applyFields(robotFields, () => say("STORE " + val("cal-robot-x") + " " + val("cal-robot-y")));
      refreshPoints();
    });
    $("cal-list").addEventListener("click", refreshPoints);
    $("cal-compute").addEventListener("click", async () => { await say("COMPUTE " + $("cal-method").value); refreshPoints(); });
    $("cal-clear").addEventListener("click", async () => {
      if (!window.confirm("Forget the whole calibration (scale, points, transform)?")) return;
      await say("CLEARCAL");
      refreshPoints();
    });
    $("cal-simulate").addEventListener("click", simulate);
  });
})();

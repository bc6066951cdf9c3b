// The Teach panel: LEARN the part inside a rectangle drawn on the image
// (LEARN <type> <name> AT x y w h, sensor pixels), the model list (MODELS,
// FORGET), and a type's grasp styles and gripper fingers (GRASP, GRIPPER)
// with their footprint drawn live on the latest located part of that type.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const grasp = { type: null, styles: [], fingers: [], mmPerPx: [1, 1] };

  async function say(pre, line) {
    const reply = await ps.command(line);
    ps.show(pre, line, reply);
    return reply;
  }

  // Groups of `size` numbers after "OK <n>".
  function groups(reply, size) {
    const f = ps.okFields(reply);
    if (!f) return [];
    const n = Number(f[0]) || 0;
    const out = [];
    for (let i = 0; i < n; ++i) out.push(f.slice(1 + i * size, 1 + (i + 1) * size));
    return out;
  }

  function showRect() {
    const r = ps.rect.teach;
    $("teach-rect-text").textContent = r ? r.x + " " + r.y + " " + r.width + " " + r.height : "none";
  }

  async function teach() {
    const r = ps.rect.teach;
    const type = Math.round(Number($("teach-type").value));
    const name = $("teach-name").value.trim();
    let line = "LEARN " + type + (name ? " " + name : "");
    if (r) line += " AT " + r.x + " " + r.y + " " + r.width + " " + r.height;
    const reply = await say("teach-reply", line);
    $("teach-reply").dataset.lastReply = reply;
    if (reply.startsWith("OK")) {
      refreshModels();
      $("grasp-type").value = type;  // its grasps next
      loadGrasp();
    }
  }

  async function refreshModels() {
    const reply = await ps.command("MODELS");
    const tbody = $("models-list").querySelector("tbody");
    tbody.textContent = "";
    for (const m of groups(reply, 5)) {
      const row = ps.tableRow(tbody, m, "Forget", async () => {
        if (!window.confirm("Forget model " + m[0] + " (" + m[1] + ") and its grasps?")) return;
        await say("teach-reply", "FORGET " + m[0]);
        refreshModels();
      });
      row.dataset.type = m[0];
      row.addEventListener("click", () => { $("grasp-type").value = m[0]; loadGrasp(); });
    }
  }

  function list(ol, items, format) {
    ol.textContent = "";
    for (const item of items) {
      const li = document.createElement("li");
      li.textContent = format(item);
      ol.appendChild(li);
    }
  }

  async function loadGrasp() {
    const type = Math.round(Number($("grasp-type").value));
    grasp.type = type;
    const status = ps.okFields(await ps.command("STATUS")) || [];
    const scale = status.find((w) => w.startsWith("scale="));
    const mm = scale && scale !== "scale=none" ? scale.slice(6).split("x").map(Number) : [1, 1];
    grasp.mmPerPx = mm.length === 2 && mm[0] > 0 && mm[1] > 0 ? mm : [1, 1];
    grasp.styles = groups(await ps.command("GRASP " + type + " LIST"), 3).map((g) => g.map(Number));
    grasp.fingers = groups(await ps.command("GRIPPER " + type + " LIST"), 4).map((g) => g.map(Number));
    list($("style-list"), grasp.styles, (s) => "x " + s[0] + "  y " + s[1] + "  rz " + s[2]);
    list($("finger-list"), grasp.fingers, (f) => "x " + f[0] + "  y " + f[1] + "  w " + f[2] + "  h " + f[3]);
    ps.drawTool();
  }

  async function graspLine(line) {
    await say("grasp-reply", line);
    loadGrasp();
  }

  // The gripper footprints of every style on the latest part of the type:
  // part frame (mm, vision axes: y up, counter-clockwise) -> sensor pixels.
  function drawFootprints(tool, m) {
    if (ps.tab !== "teach" || grasp.type === null) return;
    const result = ps.app ? ps.latest[ps.app] : null;
    const part = result && (result.parts || []).find((p) => Number(p.type || 0) === grasp.type);
    if (!part) return;
    const [mmx, mmy] = grasp.mmPerPx;
    const px = Number((part.position || {}).x || 0), py = Number((part.position || {}).y || 0);
    const phi = -Number(part.angle_deg || 0) * Math.PI / 180;  // image clockwise -> vision counter-clockwise
    const toSensor = (vx, vy) => ps.sensorToFrame(m, px + vx / mmx, py - vy / mmy);
    const rot = (a, x, y) => [x * Math.cos(a) - y * Math.sin(a), x * Math.sin(a) + y * Math.cos(a)];
    grasp.styles.forEach((s, i) => {
      const [gx, gy] = rot(phi, s[0], s[1]);
      const a = phi + s[2] * Math.PI / 180;
      const g = ps.svg(tool, "g", { class: i === 0 ? "footprint first" : "footprint", "data-style": i });
      const c = toSensor(gx, gy);
      ps.svg(g, "circle", { cx: c[0], cy: c[1], r: 3 });
      for (const f of grasp.fingers) {
        const corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(([sx, sy]) => {
          const [dx, dy] = rot(a, f[0] + sx * f[2] / 2, f[1] + sy * f[3] / 2);
          return toSensor(gx + dx, gy + dy).map((v) => v.toFixed(2)).join(" ");
        });
        ps.svg(g, "path", { d: "M" + corners.join("L") + "Z" });
      }
    });
  }

  const val = (id) => Number($(id).value) || 0;
  const gtype = () => Math.round(val("grasp-type"));

  document.addEventListener("DOMContentLoaded", () => {
    ps.toolDrawers.push(drawFootprints);
    ps.on("rect", (e) => { if (e.mode === "teach") showRect(); });
    ps.on("tab", (tab) => { if (tab === "teach") { refreshModels(); loadGrasp(); } });
    ps.on("result", () => { if (ps.tab === "teach") ps.drawTool(); });
    $("teach-button").addEventListener("click", teach);
    $("models-refresh").addEventListener("click", refreshModels);
    $("grasp-load").addEventListener("click", loadGrasp);
    $("style-add").addEventListener("click", () =>
      graspLine("GRASP " + gtype() + " ADD " + val("style-x") + " " + val("style-y") + " " + val("style-rz")));
    $("style-clear").addEventListener("click", () => graspLine("GRASP " + gtype() + " CLEAR"));
    $("finger-add").addEventListener("click", () =>
      graspLine("GRIPPER " + gtype() + " FINGER " + val("finger-x") + " " + val("finger-y") + " " +
                val("finger-w") + " " + val("finger-h")));
    $("finger-clear").addEventListener("click", () => graspLine("GRIPPER " + gtype() + " CLEAR"));
    $("grasp-type").addEventListener("change", loadGrasp);
  });
})();

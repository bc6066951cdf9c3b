// The Teach panel: LEARN the part inside a rectangle drawn on the image
// (LEARN <type> <name> AT x y w h, sensor pixels) in two steps that cannot
// replace work unseen: Teach tries it (TRYLEARN: the model, what LOCATE ALL
// would then find, drawn on the overlay, and any warning), Save stores it,
// after a confirmation naming the model it replaces; Undo takes back the
// last change to models (UNDO). The type defaults to the next free one.
// Each model's Add view reads the part again where it lies now (LEARNVIEW).
// Also the model list (MODELS, FORGET), each model's tolerances
// (TOLERANCE), and a type's grasp styles and gripper fingers (GRASP,
// GRIPPER) with their footprint drawn live on the latest located part of
// that type.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const grasp = { type: null, styles: [], fingers: [], mmPerPx: [1, 1] };
  // The models as MODELS last listed them: [type, name, area, holes, symmetry].
  let models = [];
  // The TRYLEARN whose result is shown, {type, name, args}: what Save stores.
  let pending = null;

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

  // A model name as LEARN takes it; the reason it does not, or "".
  function nameProblem(name) {
    if (name === "") return "";  // LEARN names it type<N>
    if (name.length > 32) return "the name has " + name.length + " characters, 32 at most";
    const bad = name.match(/[^A-Za-z0-9_.\-]/);
    if (!bad) return "";
    const what = bad[0] === " " ? "a space" : bad[0] === "," ? "a comma" : "'" + bad[0] + "'";
    return "the name holds " + what + ": use A-Z a-z 0-9 _ - . only (e.g. " +
           name.replace(/[^A-Za-z0-9_.\-]+/g, "_").slice(0, 32) + ")";
  }

  // The smallest type number from 1 up that has no model.
  function nextFreeType() {
    const used = new Set(models.map((m) => Number(m[0])));
    let t = 1;
    while (used.has(t)) ++t;
    return t;
  }

  const modelOf = (type) => models.find((m) => Number(m[0]) === type) || null;

  function refusal(text) {
    const pre = $("teach-reply");
    ps.show(pre, "(not sent)", "ERROR " + text);
    pre.dataset.lastReply = "ERROR " + text;
  }

  function clearPreview(why) {
    pending = null;
    $("teach-preview").hidden = true;
    $("teach-save").disabled = true;
    if (why) $("teach-preview-text").textContent = why;
  }

  // Step one: TRYLEARN with the fields and the rectangle; nothing stored.
  async function teach() {
    const r = ps.rect.teach;
    const type = Math.round(Number($("teach-type").value));
    const name = $("teach-name").value.trim();
    clearPreview();
    if (!Number.isInteger(type) || type < 0 || type > 9999 || $("teach-type").value.trim() === "") {
      refusal("the type must be an integer in [0, 9999]");
      return;
    }
    const problem = nameProblem(name);
    if (problem) {
      refusal(problem);
      return;
    }
    let args = type + (name ? " " + name : "");
    if (r) args += " AT " + r.x + " " + r.y + " " + r.width + " " + r.height;
    const reply = await say("teach-reply", "TRYLEARN " + args);
    $("teach-preview").dataset.reply = reply;
    const f = ps.okFields(reply.split(" ; ")[0]);
    if (!f || f.length < 8) return;
    await refreshModels();
    const old = modelOf(type);
    const parts = reply.split(" ; ").slice(1);
    const warnings = parts.filter((p) => p.startsWith("warning: ")).map((p) => p.slice(9));
    $("teach-preview-text").textContent =
      "Type " + f[0] + " '" + f[1] + "': " + Number(f[2]).toFixed(0) + " px\u00b2, " + f[3] + " holes. " +
      "LOCATE ALL on this frame would find " + f[6] + " of type " + f[0] + " (" + f[7] +
      " parts in all; outlines on the image). " +
      (old ? "Saving replaces type " + old[0] + " '" + old[1] + "' (its tolerances back to the defaults, its grasps kept)."
           : "Type " + f[0] + " has no model yet.");
    const list = $("teach-warnings");
    list.textContent = "";
    for (const w of warnings) {
      const li = document.createElement("li");
      li.textContent = w;
      list.appendChild(li);
    }
    pending = { type, name: f[1], args, replaces: old ? old[1] : null };
    $("teach-save").hidden = false;
    $("teach-preview").hidden = false;
    $("teach-save").disabled = false;
  }

  // Step two: LEARN what was tried, after a confirmation when it replaces a
  // model (LEARN takes a new frame: the part must still be there).
  async function save() {
    if (!pending) return;
    const p = pending;
    await refreshModels();
    const old = modelOf(p.type);
    if (old && !window.confirm("Replace model " + old[0] + " '" + old[1] + "' (area " +
                               Number(old[2]).toFixed(0) + " px\u00b2) with the new '" + p.name +
                               "'? Its tolerances go back to the defaults; Undo takes this back.")) {
      ps.show("teach-reply", "LEARN " + p.args, "not sent: model " + old[0] + " '" + old[1] + "' kept");
      return;
    }
    clearPreview();
    const reply = await say("teach-reply", "LEARN " + p.args);
    $("teach-reply").dataset.lastReply = reply;
    if (reply.startsWith("OK")) {
      ps.clearDirty($("teach-type").parentNode);  // the next free type from now on
      await refreshModels();
      ps.setField("grasp-type", p.type);  // its grasps next, unless another type is being typed
      loadGrasp();
    }
  }

  // LEARNVIEW: the part of `type` read once more where it lies now.
  async function addView(type) {
    clearPreview();
    const r = ps.rect.teach;
    let line = "LEARNVIEW " + type;
    if (r) line += " AT " + r.x + " " + r.y + " " + r.width + " " + r.height;
    const reply = await say("teach-reply", line);
    $("teach-reply").dataset.lastReply = reply;
    const f = ps.okFields(reply.split(" ; ")[0]);
    if (f && f.length >= 6) {
      $("teach-preview-text").textContent =
        "Type " + f[0] + " '" + f[1] + "': " + f[2] + " views; origin " + Number(f[3]).toFixed(3) + " " +
        Number(f[4]).toFixed(3) + " px from the first teach's centroid, views " + Number(f[5]).toFixed(3) +
        " px apart (median). Lay the part elsewhere and Add view again, or Undo.";
      $("teach-warnings").textContent = "";
      $("teach-save").hidden = true;  // stored already: nothing to save
      $("teach-preview").hidden = false;
    }
  }

  async function undo() {
    clearPreview();
    const reply = await say("teach-reply", "UNDO");
    $("teach-reply").dataset.lastReply = reply;
    await refreshModels();
    loadGrasp();
  }

  async function refreshModels() {
    const reply = await ps.command("MODELS");
    if (reply.startsWith("OK")) models = groups(reply, 5);
    ps.setField("teach-type", nextFreeType());  // unless a type is being typed
    const tbody = $("models-list").querySelector("tbody");
    tbody.textContent = "";
    for (const m of groups(reply, 5)) {
      const row = ps.tableRow(tbody, m, "Forget", async () => {
        if (!window.confirm("Forget model " + m[0] + " (" + m[1] + ") and its grasps?")) return;
        await say("teach-reply", "FORGET " + m[0]);
        refreshModels();
      });
      row.dataset.type = m[0];
      // Another view of the part (LEARNVIEW), inside the rectangle when one
      // is drawn: the part laid elsewhere under the camera, alone.
      const view = document.createElement("button");
      view.type = "button";
      view.className = "model-view";
      view.textContent = "Add view";
      view.title = "lay the part elsewhere under the camera, alone (or draw a rectangle around it), " +
                   "then Add view: the model's origin is read again there (LEARNVIEW)";
      view.addEventListener("click", (e) => { e.stopPropagation(); addView(Number(m[0])); });
      row.lastChild.prepend(view);
      row.addEventListener("click", () => { ps.setField("grasp-type", m[0], true); loadGrasp(); });
    }
    await refreshTolerances(groups(reply, 5).map((m) => m[0]));
  }

  // The tolerances TOLERANCE reports, in its order: [key, input step];
  // mirror_symmetric is a check box.
  const toleranceKeys = [["area_tolerance", "0.01"], ["hu_tolerance", "0.1"], ["verify_percent", "1"],
                         ["edge_tolerance_px", "0.1"], ["mirror_symmetric", null]];

  // {type, name, values: {key: text}} from "OK <type> <name> key=value ...".
  function parseTolerances(reply) {
    const f = ps.okFields(reply);
    if (!f || f.length < 2) return null;
    const values = {};
    for (const word of f.slice(2)) {
      const eq = word.indexOf("=");
      if (eq > 0) values[word.slice(0, eq)] = word.slice(eq + 1);
    }
    return { type: f[0], name: f[1], values };
  }

  // "0.100000" as "0.1": the fields are narrow.
  const shownValue = (t, key) => (t.values[key] === undefined ? "" : String(Number(t.values[key])));

  // A row of a model's tolerance fields; row.dataset.shown holds the values
  // the vision app last reported (what Save compares the fields with).
  function toleranceRow(tbody, t) {
    const row = document.createElement("tr");
    row.dataset.type = t.type;
    const cell = (child) => {
      const td = document.createElement("td");
      if (typeof child === "string") td.textContent = child; else td.appendChild(child);
      row.appendChild(td);
    };
    cell(t.type);
    cell(t.name);
    for (const [key, step] of toleranceKeys) {
      const input = document.createElement("input");
      input.dataset.key = key;
      input.setAttribute("data-refreshed", "");
      input.className = "tolerance-input";
      if (step) {
        input.type = "number";
        input.step = step;
      } else {
        input.type = "checkbox";
      }
      cell(input);
    }
    const save = document.createElement("button");
    save.type = "button";
    save.className = "tolerance-save";
    save.textContent = "Save";
    save.addEventListener("click", () => saveTolerances(row));
    cell(save);
    showTolerances(row, t);
    tbody.appendChild(row);
    return row;
  }

  // The values in force, in the fields the user has not edited.
  function showTolerances(row, t) {
    const before = row.dataset.shown ? JSON.parse(row.dataset.shown) : null;
    if (before && before.name !== t.name) ps.clearDirty(row);  // another model of that type
    row.dataset.shown = JSON.stringify(t);
    row.cells[1].textContent = t.name;
    for (const input of row.querySelectorAll("input[data-key]")) {
      const key = input.dataset.key;
      ps.setField(input, input.type === "checkbox" ? t.values[key] === "1" : shownValue(t, key));
    }
  }

  // Sends the changed fields of a row in one TOLERANCE line (the vision app
  // checks them all before it changes any), then shows what is in force.
  async function saveTolerances(row) {
    const t = JSON.parse(row.dataset.shown);
    const inputs = Array.from(row.querySelectorAll("input[data-key]"));
    let line = "TOLERANCE " + t.type;
    for (const input of inputs) {
      const key = input.dataset.key;
      const value = input.type === "checkbox" ? (input.checked ? "1" : "0") : input.value.trim();
      if (value !== (input.type === "checkbox" ? t.values[key] : shownValue(t, key))) line += " " + key + " " + (value === "" ? "none" : value);
    }
    if (line === "TOLERANCE " + t.type) {
      ps.clearDirty(row);  // edited back to the values in force
      ps.show("tolerance-reply", line, "nothing changed");
      return;
    }
    const reply = await ps.applyFields(inputs, () => say("tolerance-reply", line));
    const now = parseTolerances(reply);
    if (now) showTolerances(row, now);
  }

  // One row per model, in the models' order; a refresh (a tab switch,
  // another LEARN) shows the values in force but never an edited field's.
  async function refreshTolerances(types) {
    const tbody = $("tolerance-list").querySelector("tbody");
    const wanted = [];
    for (const type of types) {
      const t = parseTolerances(await ps.command("TOLERANCE " + type));
      if (t) wanted.push(t);
    }
    const rows = new Map();
    for (const row of Array.from(tbody.rows)) rows.set(row.dataset.type, row);
    for (const t of wanted) {
      let row = rows.get(t.type);
      if (row) { rows.delete(t.type); showTolerances(row, t); } else row = toleranceRow(tbody, t);
      tbody.appendChild(row);
    }
    for (const row of rows.values()) row.remove();
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
    $("grasp-type").classList.remove("dirty");  // the type shown below from now on
    const status = ps.okFields(await ps.command("STATUS")) || [];
    const scale = status.find((w) => w.startsWith("scale="));
    const mm = scale && scale !== "scale=none" ? scale.slice(6).split("x").map(Number) : [];
    const scaled = mm.length === 2 && mm[0] > 0 && mm[1] > 0;
    grasp.mmPerPx = scaled ? mm : [1, 1];
    // Before CALCAM the part frame's units are sensor pixels.
    const unit = scaled ? "mm" : "px";
    for (const el of document.querySelectorAll("#panel-teach .grasp-unit")) el.textContent = unit;
    grasp.styles = groups(await ps.command("GRASP " + type + " LIST"), 3).map((g) => g.map(Number));
    grasp.fingers = groups(await ps.command("GRIPPER " + type + " LIST"), 4).map((g) => g.map(Number));
    list($("style-list"), grasp.styles, (s) => "x " + s[0] + " " + unit + "  y " + s[1] + " " + unit + "  rz " + s[2] + "\u00b0");
    list($("finger-list"), grasp.fingers,
         (f) => "x " + f[0] + "  y " + f[1] + "  w " + f[2] + "  h " + f[3] + " " + unit);
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
    ps.on("rect", (e) => { if (e.mode === "teach") { showRect(); clearPreview("the rectangle changed: Teach again"); } });
    ps.on("tab", (tab) => { if (tab === "teach") { refreshModels(); loadGrasp(); } });
    ps.on("result", () => { if (ps.tab === "teach") ps.drawTool(); });
    $("teach-button").addEventListener("click", teach);
    $("teach-save").addEventListener("click", save);
    $("teach-cancel").addEventListener("click", () => clearPreview());
    $("teach-undo").addEventListener("click", undo);
    for (const id of ["teach-type", "teach-name"]) {
      $(id).addEventListener("input", () => {
        if (pending) clearPreview("the fields changed: Teach again");
        const problem = nameProblem($("teach-name").value.trim());
        $("teach-name-error").textContent = problem;
      });
    }
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

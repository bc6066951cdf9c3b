// PickSight web HMI, Filmstrip panel: the frames of the selected vision
// app's recent LOCATE, WHY and PLC requests with their replies (GET
// /api/apps/<app>/filmstrip, read through the app's port), failures marked;
// a click shows the frame with the parts it found, and Replay runs it
// through the models in use now (REPLAY <id>), the answer drawn beside the
// recorded one. Engineers export a set as a dir: camera's folder.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  let selected = null;  // the entry shown
  let replayLine = null;  // the REPLAY line waiting for its result event

  const imageUrl = (id, side) =>
    "/api/apps/" + encodeURIComponent(ps.app) + "/filmstrip/" + id + ".png?side=" + side;

  function when(ms) {
    const d = new Date(Number(ms));
    return isNaN(d) ? "" : d.toISOString().replace("T", " ").replace(/\.\d+Z$/, " UTC");
  }

  async function refresh() {
    const list = $("filmstrip-list");
    if (!ps.app) { $("filmstrip-note").textContent = "no vision app"; return; }
    const failures = $("filmstrip-failures").checked ? "&failures=1" : "";
    const r = await ps.get("/api/apps/" + encodeURIComponent(ps.app) + "/filmstrip?n=24" + failures);
    list.textContent = "";
    if (!r.ok) { $("filmstrip-note").textContent = r.body.error; return; }
    const entries = r.body.entries || [];
    $("filmstrip-note").textContent = entries.length ? "" : "nothing recorded yet: each LOCATE, WHY and PLC trigger is kept here";
    for (const e of entries) {
      const item = document.createElement("figure");
      item.className = "film" + (e.failure || e.error ? " failed" : "");
      item.dataset.id = e.id;
      if (e.image) {
        const img = document.createElement("img");
        img.alt = "frame of entry " + e.id;
        img.src = imageUrl(e.id, 160);
        item.appendChild(img);
      }
      const caption = document.createElement("figcaption");
      caption.textContent = "#" + e.id + " " + (e.error ? e.error : (e.request_line || e.request) + " \u2192 " + e.reply);
      item.appendChild(caption);
      if (!e.error) item.addEventListener("click", () => show(e));
      list.appendChild(item);
    }
  }

  // A sensor pixel on the shown image (which fits the frame into its box).
  function toImage(e, img, x, y) {
    const m = e.mapping || { roi_x: 0, roi_y: 0, scale_x: 1, scale_y: 1 };
    const u = (x - m.roi_x + 0.5) * m.scale_x - 0.5;
    const v = (y - m.roi_y + 0.5) * m.scale_y - 0.5;
    const k = img.clientWidth / (e.width || img.naturalWidth || 1);
    return [(u + 0.5) * k, (v + 0.5) * k];
  }

  // Marks `parts` ({x, y, offered}, sensor pixels) on the view, class `cls`.
  function mark(parts, cls) {
    const svg = $("filmstrip-marks");
    for (const old of svg.querySelectorAll("." + cls)) old.remove();
    const img = $("filmstrip-frame");
    if (!selected || !img.naturalWidth) return;
    svg.setAttribute("width", img.clientWidth);
    svg.setAttribute("height", img.clientHeight);
    for (const p of parts) {
      const [cx, cy] = toImage(selected, img, Number(p.x || 0), Number(p.y || 0));
      ps.svg(svg, "circle", { class: cls + (p.offered ? "" : " not-offered"), cx, cy, r: 7 });
    }
  }

  function show(e) {
    selected = e;
    for (const f of document.querySelectorAll("#filmstrip-list .film"))
      f.classList.toggle("selected", Number(f.dataset.id) === e.id);
    $("filmstrip-view").hidden = false;
    const lines = [
      "#" + e.id + "  " + when(e.time_ms) + "  " + (e.client || ""),
      "> " + e.request_line,
      "< " + e.reply,
    ];
    // The frame the recorded reply's poses are in (none recorded by older
    // entries, nor for replies without poses).
    if (e.reply_frame) lines.push("reply in " + ps.replyFrame(e.reply_frame).text);
    if (e.why && e.why !== e.reply) lines.push("why: " + e.why);
    if (e.camera) lines.push("camera " + e.camera + ", frame " + e.sequence + (e.width ? ", " + e.width + "x" + e.height + " px" : ""));
    // The parts as found on the image (the orange circles); the reply's
    // numbers above are in the frame named under it.
    const parts = e.parts || [];
    if (parts.length) lines.push("parts found (sensor px, y down; angle \u00b0 clockwise on the screen):");
    for (const p of parts.slice(0, 16)) {
      const type = Number(p.type || 0);
      lines.push("  " + (type >= 0 ? "type " + type : "no model") + " at x " + Number(p.x || 0).toFixed(1) +
                 ", y " + Number(p.y || 0).toFixed(1) + ", angle " + Number(p.angle_deg || 0).toFixed(1) +
                 (type >= 0 ? ", score " + Number(p.score || 0).toFixed(3) : "") + (p.offered ? "" : ", not offered"));
    }
    if (parts.length > 16) lines.push("  ... " + (parts.length - 16) + " more");
    $("filmstrip-detail").textContent = lines.join("\n");
    $("filmstrip-detail").classList.toggle("failed", !!e.failure);
    $("filmstrip-replay-reply").textContent = "";
    $("filmstrip-replay-frame").textContent = "";
    $("filmstrip-replay").disabled = !e.image;
    const img = $("filmstrip-frame");
    img.onload = () => { mark(e.parts || [], "recorded"); mark([], "replayed"); };
    img.src = e.image ? imageUrl(e.id, 1024) : "";
  }

  async function replay() {
    if (!selected) return;
    const line = "REPLAY " + selected.id;
    replayLine = line;
    mark([], "replayed");
    const reply = await ps.command(line);
    ps.show("filmstrip-replay-reply", line, reply);
    $("filmstrip-replay-reply").dataset.reply = reply;
  }

  async function exportSet() {
    const name = $("filmstrip-export-name").value.trim();
    const line = "FILMSTRIP EXPORT " + name + ($("filmstrip-failures").checked ? " FAILURES" : "");
    ps.show("filmstrip-export-reply", line, await ps.command(line));
  }

  ps.refreshFilmstrip = refresh;
  // The replay's result (published by the app once it has answered): its
  // parts drawn over the recorded ones.
  ps.on("replay", (result) => {
    if (result.app !== ps.app || result.request_line !== replayLine) return;
    const parts = (result.parts || []).map((p) => ({
      x: p.position ? p.position.x : 0, y: p.position ? p.position.y : 0, offered: p.offered,
    }));
    mark(parts, "replayed");
    $("filmstrip-marks").dataset.replayed = String(parts.length);
    $("filmstrip-replay-frame").textContent = "the replay's reply in " + ps.replyFrame(result.reply_frame).text;
    $("filmstrip-replay-frame").dataset.frame = result.reply_frame || "";
  });
  ps.on("tab", (tab) => { if (tab === "filmstrip") refresh(); });
  document.addEventListener("DOMContentLoaded", () => {
    $("filmstrip-refresh").addEventListener("click", refresh);
    $("filmstrip-failures").addEventListener("change", refresh);
    $("filmstrip-replay").addEventListener("click", replay);
    $("filmstrip-export").addEventListener("click", exportSet);
  });
})();

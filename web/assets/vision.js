// PickSight web HMI: the Vision panel. The selected vision app's settings
// (VISION) read into the fields; the newest frame binarized with the fields'
// values while they move (a live preview, /binary/<app>.png with the values
// as query parameters); Apply sends them. And the hint, here and in the Live
// panel, when the latest result's largest region looks like the surface
// rather than a part (the polarity is likely the wrong way round).
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const fields = ["vision-polarity", "vision-threshold", "vision-level", "vision-window",
                  "vision-min-area", "vision-min-hole-area"];
  const keys = ["polarity", "threshold", "level", "window", "min_area", "min_hole_area"];
  // A region whose box spans this share of the frame both ways, or whose area
  // is this share of it, is the surface more often than a part: parts are
  // placed apart on a surface larger than they are.
  const kSurfaceSpan = 0.6;
  const kSurfaceArea = 0.3;

  // "OK key=value key=value ... [; ...]" as {key: value}; null for an error.
  function settingsOf(reply) {
    if (!String(reply).startsWith("OK ")) return null;
    const head = String(reply).split(" ; ")[0];
    const out = {};
    for (const word of head.split(/\s+/).slice(1)) {
      const eq = word.indexOf("=");
      if (eq > 0) out[word.slice(0, eq)] = word.slice(eq + 1);
    }
    return out;
  }
  ps.visionSettingsOf = settingsOf;

  function showLevel() {
    $("vision-level-text").textContent = $("vision-level").value;
    // The level is the fixed threshold's alone.
    $("vision-level").disabled = $("vision-threshold").value !== "fixed";
    $("vision-window").disabled = $("vision-threshold").value !== "adaptive";
  }

  // The fields as the preview's query (what binarizes; the areas filter
  // regions after it and are not shown).
  function previewQuery() {
    const q = new URLSearchParams();
    q.set("polarity", $("vision-polarity").value);
    q.set("threshold", $("vision-threshold").value);
    q.set("level", $("vision-level").value);
    const w = parseInt($("vision-window").value, 10);
    q.set("window", Number.isFinite(w) && (w === 0 || (w >= 8 && w <= 16384)) ? String(w) : "0");
    return q.toString();
  }

  // The preview follows the fields at most every 100 ms while they move:
  // each new image is a frame binarized on the web server.
  let pending = null;
  function updatePreview() {
    const on = ps.tab === "vision" && $("vision-preview").checked;
    const query = on ? previewQuery() : null;
    if (query === ps.previewQuery) return;
    ps.previewQuery = query;
    ps.showFrame();
  }
  function schedulePreview() {
    showLevel();
    if (pending) return;
    pending = setTimeout(() => { pending = null; updatePreview(); }, 100);
  }

  async function reload(force) {
    const reply = await ps.command("VISION");
    ps.show("vision-reply", "VISION", reply);
    showReplyHint(reply);
    const s = settingsOf(reply);
    if (!s) return reply;
    keys.forEach((key, i) => { if (s[key] !== undefined) ps.setField(fields[i], s[key], force); });
    showLevel();
    updatePreview();
    return reply;
  }
  ps.reloadVision = reload;

  // A button that previews `polarity` in the Vision panel.
  function tryButton(polarity) {
    const b = document.createElement("button");
    b.type = "button";
    b.className = "try-polarity";
    b.textContent = "Try polarity " + polarity;
    b.addEventListener("click", () => {
      ps.selectTab("vision");
      ps.setField("vision-polarity", polarity, true, true);
      schedulePreview();
    });
    return b;
  }

  // VISION's " ; hint: ..." (most of the last frame taken for part), with a
  // button for the polarity it names.
  function showReplyHint(reply) {
    const el = $("vision-hint");
    const hint = String(reply).split(" ; ").find((part) => part.startsWith("hint: "));
    el.textContent = "";
    el.hidden = !hint;
    if (!hint) return;
    const polarity = hint.endsWith("polarity light") ? "light" : "dark";
    el.append(document.createTextNode(hint.slice("hint: ".length) + ". "), tryButton(polarity));
  }

  function showReteach(reply) {
    const list = $("vision-reteach");
    list.textContent = "";
    for (const part of String(reply).split(" ; ").slice(1)) {
      if (!part.startsWith("re-teach: ")) continue;
      const li = document.createElement("li");
      li.textContent = "re-teach type " + part.slice("re-teach: ".length) +
                       " (Teach tab: LEARN it again under these settings)";
      list.appendChild(li);
    }
  }

  async function apply() {
    const values = fields.map((id) => String($(id).value).trim());
    const line = "VISION " + keys.map((k, i) => k + " " + (values[i] || "?")).join(" ");
    const reply = await ps.applyFields(fields, () => ps.command(line));
    ps.show("vision-reply", line, reply);
    $("vision-reply").dataset.lastReply = reply;
    showReteach(reply);
    if (reply.startsWith("OK")) await reload(true);
    return reply;
  }
  ps.applyVision = apply;

  // The region of `result` that looks like the surface, or null: frame
  // sizes in sensor pixels, as the regions' boxes and areas are.
  function surfaceRegion(result) {
    const w = (result.frame_width || 0) / (result.scale_x || 1);
    const h = (result.frame_height || 0) / (result.scale_y || 1);
    if (!w || !h) return null;
    for (const r of result.regions || []) {
      const spans = (r.box_width || 0) >= kSurfaceSpan * w && (r.box_height || 0) >= kSurfaceSpan * h;
      if (spans || (r.area || 0) >= kSurfaceArea * w * h) return r;
    }
    return null;
  }

  function showHint(result) {
    if (!result || result.app !== ps.app || !result.binarize) return;
    const region = surfaceRegion(result);
    const dark = result.binarize.dark_parts !== false;
    const other = dark ? "light" : "dark";
    for (const id of ["vision-polarity-hint", "live-polarity-hint"]) {
      const el = $(id);
      el.textContent = "";
      el.hidden = !region;
      if (!region) continue;
      const text = document.createElement("span");
      text.textContent = "Region " + (region.index || 0) + " covers most of the image (" +
        Math.round(region.area || 0) + " px\u00b2, " + (region.holes || 0) + " holes): the surface is " +
        "probably taken for a part. Parts " + (dark ? "lighter" : "darker") + " than their surface need polarity " +
        other + ". ";
      el.append(text, tryButton(other));
    }
  }
  ps.surfaceRegion = surfaceRegion;

  document.addEventListener("DOMContentLoaded", () => {
    for (const id of fields) {
      $(id).addEventListener("input", schedulePreview);
      $(id).addEventListener("change", schedulePreview);
    }
    $("vision-preview").addEventListener("change", updatePreview);
    $("vision-apply").addEventListener("click", apply);
    $("vision-reload").addEventListener("click", () => { ps.clearDirty($("panel-vision")); reload(true); });
    ps.on("tab", (tab) => {
      if (tab === "vision") reload(false); else updatePreview();
    });
    ps.on("camera", () => { if (ps.tab === "vision") reload(false); });
    ps.on("result", showHint);
    showLevel();
  });
})();

// The Camera panel: open/close, mode (free-run, software or hardware
// trigger with its input, edge and timeout), trigger, exposure and gain, the ROI
// drawn on the image (sensor pixels), output size, and any feature by name,
// all through picksight-web's camera endpoints (the video server's control
// socket).
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  let features = [];

  // The first feature the camera has of a list of usual names (GenICam,
  // V4L2), else the first name, which the server then refuses with a message.
  function featureName(candidates) {
    for (const name of candidates) if (features.some((f) => f.name === name)) return name;
    return candidates[0];
  }
  const exposureName = () => featureName(["ExposureTime", "ExposureTimeAbs", "exposure_time_absolute"]);
  const gainName = () => featureName(["Gain", "GainRaw", "gain"]);

  function featureValue(name) {
    const f = features.find((x) => x.name === name);
    return f ? f.value : "";
  }

  // The feature's unit as the camera names it ("us", "100us", "dB"...);
  // "" when it names none, or has no such feature.
  function featureUnit(name) {
    const f = features.find((x) => x.name === name);
    return f && f.unit ? f.unit : "";
  }

  async function refreshFeatures() {
    if (!ps.camera) return;
    const r = await ps.get("/api/cameras/" + encodeURIComponent(ps.camera) + "/features");
    if (!r.ok) { ps.show("camera-reply", "features", "ERROR " + r.body.error); return; }
    features = Array.isArray(r.body) ? r.body : r.body.features || [];
    const tbody = $("feature-list").querySelector("tbody");
    tbody.textContent = "";
    $("feature-names").textContent = "";
    for (const f of features) {
      const range = f.choices && f.choices.length ? f.choices.join(" | ")
        : f.has_range ? (f.min || 0) + " .. " + (f.max || 0) + (f.unit ? " " + f.unit : "") : "";
      const row = ps.tableRow(tbody, [f.name, f.value === undefined ? "" : String(f.value), f.unit || "", range]);
      row.addEventListener("click", () => {
        ps.setField("feature-name", f.name, true);
        ps.setField("feature-value", f.value === undefined ? "" : f.value, true);
      });
      const o = document.createElement("option");
      o.value = f.name;
      $("feature-names").appendChild(o);
    }
    ps.setField("cam-exposure", featureValue(exposureName()));
    ps.setField("cam-gain", featureValue(gainName()));
    $("cam-exposure-unit").textContent = featureUnit(exposureName());
    $("cam-gain-unit").textContent = featureUnit(gainName());
  }

  // Sets a feature to the value of its field(s); the list and the exposure
  // and gain fields are read back.
  async function setFeature(name, fields) {
    if (!name) return;
    const value = $(fields[fields.length - 1]).value;
    await ps.applyFields(fields, () => ps.cameraAction("feature", { name, value: String(value) }));
    refreshFeatures();
  }

  const roiFields = ["roi-x", "roi-y", "roi-w", "roi-h"];

  // The camera's ROI, or a rectangle just dragged on the image: that one
  // replaces any edit and stays marked until it is applied.
  function showRoi(rect) {
    const c = ps.cameraInfo() || {};
    const r = rect || c.roi || {};
    [r.x, r.y, r.width, r.height].forEach((v, i) => ps.setField(roiFields[i], v || 0, !!rect, !!rect));
  }

  function showCamera() {
    const c = ps.cameraInfo();
    if (!c) return;
    for (const radio of document.querySelectorAll("input[name=cam-mode]")) radio.checked = radio.value === c.mode;
    if (c.trigger_line) ps.setField("cam-hw-line", c.trigger_line);
    if (c.trigger_activation !== undefined) ps.setField("cam-hw-activation", c.trigger_activation);
    if (c.trigger_timeout_ms) ps.setField("cam-hw-timeout", c.trigger_timeout_ms);
    showRoi();
    ps.setField("size-w", c.width || 0);
    ps.setField("size-h", c.height || 0);
  }

  const intOf = (id) => Math.max(0, Math.round(Number($(id).value) || 0));

  // The hardware mode with the input, edge and timeout of the fields (empty
  // ones left to the video server's defaults).
  const hwFields = ["cam-hw-line", "cam-hw-activation", "cam-hw-timeout"];
  function hardwareMode() {
    const body = { mode: "hardware" };
    const line = $("cam-hw-line").value.trim();
    if (line) body.line = line;
    if ($("cam-hw-activation").value) body.activation = $("cam-hw-activation").value;
    const ms = intOf("cam-hw-timeout");
    if (ms > 0) body.timeout_ms = ms;
    return ps.applyFields(hwFields, () => ps.cameraAction("mode", body));
  }

  document.addEventListener("DOMContentLoaded", () => {
    ps.on("camera", () => { ps.rect.roi = null; showCamera(); refreshFeatures(); });
    ps.on("cameras", showCamera);
    ps.on("tab", (tab) => { if (tab === "camera") refreshFeatures(); });
    ps.on("rect", (e) => { if (e.mode === "roi") showRoi(e.rect); });
    $("cam-open").addEventListener("click", () => ps.cameraAction("open"));
    $("cam-close").addEventListener("click", () => ps.cameraAction("close"));
    $("cam-trigger").addEventListener("click", () => ps.cameraAction("trigger"));
    for (const radio of document.querySelectorAll("input[name=cam-mode]")) {
      radio.addEventListener("change", () =>
        radio.value === "hardware" ? hardwareMode() : ps.cameraAction("mode", { mode: radio.value }));
    }
    $("cam-hw-apply").addEventListener("click", hardwareMode);
    $("cam-exposure-set").addEventListener("click", () => setFeature(exposureName(), ["cam-exposure"]));
    $("cam-gain-set").addEventListener("click", () => setFeature(gainName(), ["cam-gain"]));
    $("roi-apply").addEventListener("click", async () => {
      const body = { x: intOf("roi-x"), y: intOf("roi-y"), width: intOf("roi-w"), height: intOf("roi-h") };
      const r = await ps.applyFields(roiFields, () => ps.cameraAction("roi", body));
      if (r.ok) { ps.rect.roi = null; ps.drawTool(); }
    });
    $("roi-full").addEventListener("click", async () => {
      const r = await ps.cameraAction("roi", { x: 0, y: 0, width: 0, height: 0 });
      // The full sensor replaces whatever the ROI fields held.
      if (r.ok) { ps.rect.roi = null; ps.drawTool(); ps.clearDirty($("roi-fields")); }
    });
    $("size-apply").addEventListener("click", () => ps.applyFields(["size-w", "size-h"],
      () => ps.cameraAction("size", { width: intOf("size-w"), height: intOf("size-h") })));
    $("scale-apply").addEventListener("click", () => ps.cameraAction("size", { scale: Number($("size-scale").value) || 1 }));
    $("feature-set").addEventListener("click", () => setFeature($("feature-name").value.trim(), ["feature-name", "feature-value"]));
    $("feature-refresh").addEventListener("click", refreshFeatures);
  });
})();

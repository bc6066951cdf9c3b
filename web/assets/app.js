// PickSight web HMI core: state, HTTP helpers, the live frame with its
// sensor-pixel mapping, Server-Sent Events, tabs and the rectangle tool.
// Panels (overlay.js, camera.js, vision.js, teach.js, calibrate.js) register on
// window.picksight; everything runs on the browser's one thread.
"use strict";

(function () {
  const ps = {
    cameras: [],        // the latest /api/cameras (or event: cameras)
    apps: [],           // /api/apps
    camera: null,       // selected camera name
    app: null,          // selected vision app name
    latest: {},         // app name -> latest VisionResult (JSON)
    lastOverlay: null,  // what overlay.js drew last (read by the tests)
    tab: "live",
    listeners: { camera: [], result: [], cameras: [], tab: [], rect: [], frame: [], replay: [] },
    errors: [],         // failed requests, newest last (also shown on the page)
  };
  window.picksight = ps;

  const $ = (id) => document.getElementById(id);
  ps.$ = $;

  ps.on = function (what, fn) { ps.listeners[what].push(fn); };
  function emit(what, arg) {
    for (const fn of ps.listeners[what]) {
      try { fn(arg); } catch (e) { console.warn("picksight:", what, e); }
    }
  }

  // ---- HTTP ----------------------------------------------------------------
  // Every request resolves (never rejects): {ok, status, body} with body the
  // parsed JSON or {error: text}, so a panel shows the server's message.
  ps.request = async function (method, url, body) {
    const init = { method, headers: {}, credentials: "same-origin" };
    // The server refuses changes without this header: a cross-site page
    // cannot add it, nor post JSON, without a preflight it never grants.
    if (method !== "GET") init.headers["X-PickSight"] = "1";
    if (body !== undefined) {
      init.headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(body);
    }
    try {
      const r = await fetch(url, init);
      const text = await r.text();
      let parsed;
      try { parsed = text ? JSON.parse(text) : {}; } catch (e) { parsed = { error: text }; }
      if (!r.ok && !parsed.error) parsed.error = "HTTP " + r.status;
      // A session that ended (logout elsewhere, expiry): log in again.
      if (r.status === 401 && url !== "/api/login" && ps.user) showLogin("session ended: log in again");
      return { ok: r.ok, status: r.status, body: parsed };
    } catch (e) {
      return { ok: false, status: 0, body: { error: String(e) } };
    }
  };
  ps.get = (url) => ps.request("GET", url);
  ps.post = (url, body) => ps.request("POST", url, body === undefined ? {} : body);

  // One robot-protocol line to the selected app: the reply line, or
  // "ERROR <http message>" when the app cannot be reached.
  ps.command = async function (line, app) {
    const name = app || ps.app;
    if (!name) return "ERROR no vision app";
    const r = await ps.post("/api/apps/" + encodeURIComponent(name) + "/command", { line });
    const reply = r.ok ? String(r.body.reply) : "ERROR " + r.body.error;
    ps.log(line, reply);
    return reply;
  };

  // Writes "> line / < reply" into a <pre>, newest first, bounded.
  ps.show = function (pre, line, reply) {
    const el = typeof pre === "string" ? $(pre) : pre;
    const lines = ("> " + line + "\n< " + reply + "\n" + el.textContent).split("\n");
    el.textContent = lines.slice(0, 40).join("\n");
    el.classList.toggle("failed", reply.startsWith("ERROR"));
  };
  ps.log = function () {};  // replaced by tests when they want a trace

  // Numbers after "OK" of a reply line; null for an error.
  ps.okFields = function (reply) {
    const w = String(reply).trim().split(/\s+/);
    if (w[0] !== "OK") return null;
    return w.slice(1);
  };

  // The frame a result's reply poses are in (VisionResult.reply_frame;
  // STATUS frame=), as the page names it: {text, short, title}. Image
  // positions are sensor pixels with y down; every reply frame has y up
  // and angles counter-clockwise (docs/PROTOCOL.md, "Coordinates").
  const replyFrames = {
    pixels: { text: "vision px (y up; no CALCAM yet)", short: "vision px",
              title: "the vision frame in sensor pixels: origin at pixel (0, 0), x right, y UP the image " +
                     "(image y negated), rz counter-clockwise (STATUS frame=vision-px)" },
    vision_mm: { text: "vision mm (y up; CALCAM, no COMPUTE yet)", short: "vision mm",
                 title: "the vision frame in millimetres: origin at pixel (0, 0), x right, y UP the image, " +
                        "rz counter-clockwise (STATUS frame=vision-mm)" },
    robot_mm: { text: "robot mm (robot frame)", short: "robot mm",
                title: "the robot's base frame in millimetres, rz in degrees counter-clockwise, through the " +
                       "transform COMPUTE found (STATUS frame=robot)" },
  };
  ps.replyFrame = function (name) {
    if (!name) return { text: "no frame (this request replies no pose)", short: "-", title: "" };
    return replyFrames[name] || { text: "'" + name + "' (a frame this page does not know)", short: name,
                                  title: "STATUS frame= names it" };
  };

  // Appends a row of text cells to a table body, with a last cell holding
  // one button when `button` is given; the row.
  ps.tableRow = function (tbody, texts, button, onClick) {
    const row = document.createElement("tr");
    for (const text of texts) {
      const td = document.createElement("td");
      td.textContent = text;
      row.appendChild(td);
    }
    if (button) {
      const td = document.createElement("td");
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = button;
      b.addEventListener("click", (e) => { e.stopPropagation(); onClick(); });
      td.appendChild(b);
      row.appendChild(td);
    }
    tbody.appendChild(row);
    return row;
  };

  // ---- fields refreshed from the server ------------------------------------------
  // An input marked data-refreshed shows a value the server holds and is
  // rewritten by refreshes. Once the user edits it (an input or change event,
  // which a script's writes never fire) it is dirty, class "dirty", until the
  // server accepts the value (ps.applyFields) or the user selects another
  // camera or app: a refresh never overwrites it, so a value typed and left
  // for the Apply button is still there when the button is pressed.
  const fieldOf = (f) => (typeof f === "string" ? $(f) : f);
  const valueOf = (el) => (el.type === "checkbox" ? el.checked : el.value);
  ps.isDirty = (f) => fieldOf(f).classList.contains("dirty");

  // Shows the server's value unless the user's edit is pending; with
  // `force` (the user asked for this value: a rectangle dragged, a row
  // picked) it replaces the edit and leaves the field dirty when `dirty`.
  ps.setField = function (f, value, force, dirty) {
    const el = fieldOf(f);
    if (!force && ps.isDirty(el)) return false;
    if (el.type === "checkbox") el.checked = !!value; else el.value = value;
    el.classList.toggle("dirty", !!dirty);
    return true;
  };

  // Sends the fields' values with `send` (a camera action's {ok} or a
  // protocol reply line); when the server accepts, the fields still holding
  // what was sent are clean again (a refused edit stays dirty, with the
  // refusal shown beside it). The result of `send`.
  ps.applyFields = async function (fields, send) {
    const els = fields.map(fieldOf);
    const sent = els.map(valueOf);
    const r = await send();
    const ok = typeof r === "string" ? r.startsWith("OK") : !!(r && r.ok);
    if (ok) els.forEach((el, i) => { if (valueOf(el) === sent[i]) el.classList.remove("dirty"); });
    return r;
  };

  ps.clearDirty = function (root) {
    for (const el of (root || document).querySelectorAll(".dirty")) el.classList.remove("dirty");
  };

  function markDirty(e) {
    const el = e.target;
    if (el && el.hasAttribute && el.hasAttribute("data-refreshed")) el.classList.add("dirty");
  }
  document.addEventListener("input", markDirty, true);
  document.addEventListener("change", markDirty, true);

  // A camera action; shows the server's message in the camera panel.
  ps.cameraAction = async function (action, body) {
    if (!ps.camera) return { ok: false, body: { error: "no camera" } };
    const url = "/api/cameras/" + encodeURIComponent(ps.camera) + "/" + action;
    const r = await ps.post(url, body);
    ps.show("camera-reply", action + " " + JSON.stringify(body || {}),
            r.ok ? JSON.stringify(r.body) : "ERROR " + r.body.error);
    if (r.ok) refreshCameras();
    return r;
  };

  // ---- cameras and the frame mapping ----------------------------------------
  ps.cameraInfo = function (name) {
    return ps.cameras.find((c) => c.name === (name || ps.camera)) || null;
  };

  // The displayed frame's mapping to sensor pixels: a frame pixel (u, v) lies
  // at sensor pixel roi + (u + 0.5) / scale - 0.5 (docs/ARCHITECTURE.md).
  // Missing JSON fields are 0; a zero ROI size means the full sensor.
  ps.mapping = function () {
    const c = ps.cameraInfo() || {};
    const roi = c.roi || {};
    const img = $("frame");
    const fw = img.naturalWidth || c.width || 640;
    const fh = img.naturalHeight || c.height || 480;
    const sx = c.scale_x > 0 ? c.scale_x : (roi.width ? fw / roi.width : 1);
    const sy = c.scale_y > 0 ? c.scale_y : (roi.height ? fh / roi.height : 1);
    return {
      roiX: roi.x || 0, roiY: roi.y || 0, scaleX: sx, scaleY: sy, frameW: fw, frameH: fh,
      sensorW: c.sensor_width || fw / sx, sensorH: c.sensor_height || fh / sy,
    };
  };

  // Sensor pixel (centre coordinates) -> overlay user units (frame pixels,
  // edge coordinates: the frame spans 0..frameW).
  ps.sensorToFrame = function (m, x, y) {
    return [(x - m.roiX + 0.5) * m.scaleX, (y - m.roiY + 0.5) * m.scaleY];
  };
  // Overlay user units -> CSS pixels from the image's top-left corner.
  ps.frameToDisplay = function (m, u, v) {
    const r = $("frame").getBoundingClientRect();
    return [u * r.width / m.frameW, v * r.height / m.frameH];
  };
  // CSS pixels from the image's top-left -> sensor edge coordinates (pixel i
  // spans [i, i + 1)), for rectangles drawn with the mouse.
  ps.displayToSensorEdge = function (m, dx, dy) {
    const r = $("frame").getBoundingClientRect();
    return [dx * m.frameW / r.width / m.scaleX + m.roiX, dy * m.frameH / r.height / m.scaleY + m.roiY];
  };

  // ---- the frame: MJPEG stream, or the binarized image on demand ------------
  let binaryTimer = null;
  // Counts showFrame() calls: a binarized image's load that settles after
  // the frame was switched again schedules nothing.
  let frameGeneration = 0;
  ps.binaryWanted = false;
  // The Vision panel's preview: query parameters (polarity, threshold,
  // level, window) that replace the app's settings in the binarized image;
  // null when no preview is shown.
  ps.previewQuery = null;
  function showFrame() {
    const img = $("frame");
    if (binaryTimer) { clearTimeout(binaryTimer); binaryTimer = null; }
    const generation = ++frameGeneration;
    if (!ps.camera) { img.removeAttribute("src"); return; }
    // The server binarizes the frame of the app's camera with the settings
    // of its latest result: none before the app's first vision request.
    const wanted = ps.binaryWanted || ps.previewQuery !== null;
    const binary = wanted && ps.app && ps.latest[ps.app];
    $("live-binary-note").textContent = wanted && !binary ? "after the app's first vision request" : "";
    if (binary) {
      const query = ps.previewQuery ? ps.previewQuery + "&" : "";
      // The next image a second after the last one settled, never on a
      // fixed clock: the server makes them at idle priority, and on a busy
      // machine one can take seconds; a new src every second would cancel
      // each before it arrived and the image would never show.
      const load = () => {
        const settled = () => {
          img.removeEventListener("load", settled);
          img.removeEventListener("error", settled);
          if (generation === frameGeneration) binaryTimer = setTimeout(load, 1000);
        };
        img.addEventListener("load", settled);
        img.addEventListener("error", settled);
        img.src = "/binary/" + encodeURIComponent(ps.app) + ".png?" + query + "t=" + Date.now();
      };
      load();
    } else {
      img.src = "/stream/" + encodeURIComponent(ps.camera) + ".mjpg";
    }
  }
  ps.showFrame = showFrame;

  // The frame as large as the column and the window allow, keeping its
  // aspect (the overlay layers follow the image element's box), with the
  // status lines under it in the window: the page does not scroll. Those
  // lines have a fixed height (style.css), so the fit depends only on the
  // window and the frame's aspect, never on the texts shown.
  function fitFrame() {
    const img = $("frame");
    if (!img.naturalWidth || !img.naturalHeight) return;
    const viewer = $("viewer").getBoundingClientRect();
    const below = $("view-column").getBoundingClientRect().bottom - viewer.bottom +
                  parseFloat(getComputedStyle(document.querySelector("main")).paddingBottom);
    const maxW = $("view-column").clientWidth;
    const maxH = Math.max(200, window.innerHeight - (viewer.top + window.scrollY) - below);
    const w = Math.floor(Math.min(maxW, maxH * img.naturalWidth / img.naturalHeight));
    if (img.style.width !== w + "px") img.style.width = w + "px";
  }
  ps.fitFrame = fitFrame;

  // A frame of another size or aspect (the camera's ROI or output size
  // changed) replaces the previous one in the MJPEG stream without a load
  // event, and often before the camera event that announces it. The image
  // kept the width fitted to the previous aspect until that event (up to a
  // second) and then jumped under a rectangle being drawn. The natural size
  // is checked before every paint: a new one is fitted (event "frame")
  // before it is first shown.
  let frameSize = "";
  function watchFrameSize() {
    const img = $("frame");
    const size = img.naturalWidth + "x" + img.naturalHeight;
    if (size !== frameSize) {
      frameSize = size;
      emit("frame", size);
    }
    window.requestAnimationFrame(watchFrameSize);
  }

  function sizeLayers() {
    fitFrame();
    const m = ps.mapping();
    const box = "0 0 " + m.frameW + " " + m.frameH;
    for (const id of ["overlay", "tool"]) {
      if ($(id).getAttribute("viewBox") !== box) $(id).setAttribute("viewBox", box);
    }
  }
  ps.sizeLayers = sizeLayers;

  // ---- camera and app lists --------------------------------------------------
  function fillSelect(select, names, current) {
    const now = Array.from(select.options).map((o) => o.value).join("\n");
    if (now !== names.join("\n")) {
      select.textContent = "";
      for (const n of names) {
        const o = document.createElement("option");
        o.value = n; o.textContent = n;
        select.appendChild(o);
      }
    }
    if (current !== null) select.value = current;
  }

  function appsOfCamera() {
    const mine = ps.apps.filter((a) => a.camera === ps.camera).map((a) => a.name);
    return mine.length ? mine : ps.apps.map((a) => a.name);
  }

  // An app's newest result, from the event stream or fetched when the app
  // is chosen: a binarized image asked for before the app's first known
  // result is shown once it is known.
  function noteResult(result) {
    const first = !ps.latest[result.app];
    ps.latest[result.app] = result;
    if (first && result.app === ps.app && (ps.binaryWanted || ps.previewQuery !== null)) showFrame();
    emit("result", result);
  }

  function selectApp(name) {
    ps.app = name || null;
    fillSelect($("app-select"), appsOfCamera(), ps.app);
    // Only an app that has results: a 404 would be a console error.
    const entry = ps.apps.find((a) => a.name === ps.app);
    if (entry && Number(entry.last_result_id || 0) > 0 && !ps.latest[ps.app]) {
      ps.get("/api/results/" + encodeURIComponent(ps.app) + "/latest").then((r) => {
        if (r.ok && !ps.latest[ps.app]) noteResult(r.body);
      });
    }
  }

  function selectCamera(name) {
    if (name === ps.camera) return;
    ps.camera = name;
    ps.clearDirty();  // the fields now show another camera's values
    localStorage.setItem("picksight.camera", name);
    fillSelect($("camera-select"), ps.cameras.map((c) => c.name), name);
    const apps = appsOfCamera();
    selectApp(apps.includes(ps.app) ? ps.app : apps[0]);
    showFrame();
    showStats();
    emit("camera", name);
  }
  ps.selectCamera = selectCamera;

  function showStats() {
    const c = ps.cameraInfo();
    const text = (id, v) => { $(id).textContent = v; };
    if (!c) return;
    text("stat-state", c.state || "-");
    text("stat-sequence", c.sequence || 0);
    text("stat-fps", Number(c.fps || 0).toFixed(1));
    text("stat-drops", c.drops || 0);
    text("stat-reconnects", c.reconnects || 0);
    text("stat-size", (c.width || 0) + "x" + (c.height || 0) + " px");
    const r = c.roi || {};
    text("stat-roi", (r.x || 0) + "," + (r.y || 0) + " " + (r.width || 0) + "x" + (r.height || 0) + " px");
    text("stat-error", c.last_error || "");
    $("stat-error").title = c.last_error || "";  // the whole text; the line shows what fits
    document.body.classList.toggle("simulated", !!c.simulated_robot);
  }

  ps.cameraRefreshes = 0;  // camera lists shown so far (read by the tests)
  function setCameras(list) {
    if (!Array.isArray(list)) return;
    ps.cameras = list;
    const names = list.map((c) => c.name);
    fillSelect($("camera-select"), names, ps.camera);
    if (!ps.camera || !names.includes(ps.camera)) {
      const saved = localStorage.getItem("picksight.camera");
      if (names.length) selectCamera(names.includes(saved) ? saved : names[0]);
    }
    showStats();
    sizeLayers();
    emit("cameras", list);
    ++ps.cameraRefreshes;
  }

  async function refreshCameras() {
    const r = await ps.get("/api/cameras");
    if (r.ok) setCameras(r.body);
  }
  ps.refreshCameras = refreshCameras;

  async function refreshApps() {
    const r = await ps.get("/api/apps");
    if (!r.ok || !Array.isArray(r.body)) return;
    ps.apps = r.body;
    const apps = appsOfCamera();
    selectApp(apps.includes(ps.app) ? ps.app : apps[0]);
  }

  // ---- Server-Sent Events ------------------------------------------------------
  function connectEvents() {
    const source = new EventSource("/events");
    const badge = $("connection");
    source.onopen = () => { badge.textContent = "live"; badge.className = "badge ok"; };
    source.onerror = () => { badge.textContent = "reconnecting"; badge.className = "badge bad"; };
    source.addEventListener("cameras", (e) => {
      try { setCameras(JSON.parse(e.data)); } catch (err) { console.warn("picksight: cameras event", err); }
    });
    source.addEventListener("result", (e) => {
      let result;
      try { result = JSON.parse(e.data); } catch (err) { console.warn("picksight: result event", err); return; }
      if (!result.app) return;
      // A filmstrip replay is of a recorded frame, not the live one: for
      // the Filmstrip panel alone.
      if (result.request === "REPLAY") { emit("replay", result); return; }
      noteResult(result);
    });
  }

  // ---- tabs ---------------------------------------------------------------------
  function selectTab(tab) {
    ps.tab = tab;
    for (const b of document.querySelectorAll("#tabs button")) b.classList.toggle("active", b.dataset.tab === tab);
    for (const p of document.querySelectorAll(".panel")) p.classList.toggle("active", p.id === "panel-" + tab);
    const modes = { camera: "roi", teach: "teach" };
    $("viewer").dataset.mode = modes[tab] || "none";
    const hints = { camera: "drag on the image: ROI", teach: "drag on the image: the part to teach" };
    $("tool-hint").textContent = hints[tab] || "";
    emit("tab", tab);
  }
  ps.selectTab = selectTab;

  // ---- rectangle tool: drag on the image, in the Camera and Teach tabs ----------
  // The rectangle is kept in sensor edge coordinates (what LEARN AT and the
  // ROI take), so it stays on the part when the frame's ROI or size change.
  ps.rect = { roi: null, teach: null };
  function rectTool() {
    const tool = $("tool");
    let start = null;
    const local = (e) => {
      const r = $("frame").getBoundingClientRect();
      return [Math.min(Math.max(e.clientX - r.left, 0), r.width), Math.min(Math.max(e.clientY - r.top, 0), r.height)];
    };
    const toSensorRect = (a, b) => {
      const m = ps.mapping();
      const p = ps.displayToSensorEdge(m, Math.min(a[0], b[0]), Math.min(a[1], b[1]));
      const q = ps.displayToSensorEdge(m, Math.max(a[0], b[0]), Math.max(a[1], b[1]));
      const x0 = Math.max(0, Math.round(p[0])), y0 = Math.max(0, Math.round(p[1]));
      const x1 = Math.min(Math.round(m.sensorW), Math.round(q[0]));
      const y1 = Math.min(Math.round(m.sensorH), Math.round(q[1]));
      return { x: x0, y: y0, width: Math.max(0, x1 - x0), height: Math.max(0, y1 - y0) };
    };
    tool.addEventListener("mousedown", (e) => {
      const mode = $("viewer").dataset.mode;
      if (mode === "none" || e.button !== 0) return;
      e.preventDefault();
      start = local(e);
    });
    window.addEventListener("mousemove", (e) => {
      if (!start) return;
      const mode = $("viewer").dataset.mode;
      ps.rect[mode] = toSensorRect(start, local(e));
      drawRects();
    });
    window.addEventListener("mouseup", (e) => {
      if (!start) return;
      const mode = $("viewer").dataset.mode;
      const rect = toSensorRect(start, local(e));
      start = null;
      ps.rect[mode] = rect.width > 0 && rect.height > 0 ? rect : null;
      drawRects();
      emit("rect", { mode, rect: ps.rect[mode] });
    });
  }

  const SVG = "http://www.w3.org/2000/svg";
  ps.svg = function (parent, tag, attrs, text) {
    const el = document.createElementNS(SVG, tag);
    for (const k in attrs) el.setAttribute(k, attrs[k]);
    if (text !== undefined) el.textContent = text;
    parent.appendChild(el);
    return el;
  };

  // The tool layer: the rectangle of the current tab, and what panels add
  // (grasp footprints, calibration arrows) through ps.toolDrawers.
  ps.toolDrawers = [];
  function drawRects() {
    const tool = $("tool");
    tool.textContent = "";
    sizeLayers();
    const m = ps.mapping();
    const mode = $("viewer").dataset.mode;
    const r = ps.rect[mode];
    if (r) {
      const a = [(r.x - m.roiX) * m.scaleX, (r.y - m.roiY) * m.scaleY];
      ps.svg(tool, "rect", {
        id: mode + "-rect", class: "drag-rect", x: a[0], y: a[1],
        width: r.width * m.scaleX, height: r.height * m.scaleY,
        "data-x": r.x, "data-y": r.y, "data-width": r.width, "data-height": r.height,
      });
    }
    for (const draw of ps.toolDrawers) {
      try { draw(tool, m); } catch (e) { console.warn("picksight: tool layer", e); }
    }
  }
  ps.drawTool = drawRects;

  // ---- users -------------------------------------------------------------------
  // The session is an HttpOnly cookie the script never sees: /api/session
  // says who is logged in, and the page starts its feeds only then.
  ps.user = null;  // {user, role} once logged in
  function showLogin(message) {
    ps.user = null;
    $("login-error").textContent = message || "";
    $("login").hidden = false;
    $("login-user").focus();
  }
  function showUser() {
    $("login").hidden = true;
    $("user-name").textContent = ps.user.user + " (" + ps.user.role + ")";
    document.body.dataset.role = ps.user.role;
  }
  let started = false;
  function startLive() {
    if (started) return;
    started = true;
    refreshCameras().then(refreshApps);
    setInterval(refreshApps, 5000);
    connectEvents();
  }
  async function login() {
    const r = await ps.request("POST", "/api/login",
                               { user: $("login-user").value, password: $("login-password").value });
    $("login-password").value = "";
    if (!r.ok) { $("login-error").textContent = r.body.error; return; }
    const again = started;
    ps.user = r.body;
    showUser();
    // The event stream gave up on the ended session: start it afresh.
    if (again) location.reload(); else startLive();
  }
  ps.login = login;

  // ---- start -------------------------------------------------------------------
  document.addEventListener("DOMContentLoaded", () => {
    $("login-form").addEventListener("submit", (e) => { e.preventDefault(); login(); });
    $("logout").addEventListener("click", async () => {
      await ps.post("/api/logout");
      location.reload();
    });
    for (const b of document.querySelectorAll("#tabs button")) b.addEventListener("click", () => selectTab(b.dataset.tab));
    $("camera-select").addEventListener("change", (e) => selectCamera(e.target.value));
    $("app-select").addEventListener("change", (e) => {
      ps.clearDirty();
      selectApp(e.target.value);
      emit("camera", ps.camera);
    });
    $("frame").addEventListener("load", () => { sizeLayers(); drawRects(); });
    window.addEventListener("resize", () => emit("camera", ps.camera));
    ps.on("camera", drawRects);
    ps.on("tab", drawRects);
    ps.on("cameras", drawRects);
    ps.on("frame", drawRects);
    watchFrameSize();
    rectTool();
    ps.get("/api/session").then((r) => {
      if (!r.ok || !r.body.user) return showLogin();
      ps.user = r.body;
      showUser();
      startLive();
    });
  });
})();

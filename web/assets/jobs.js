// PickSight web HMI: the Jobs panel. The selected vision app's jobs (JOB
// LIST) and the one in force (JOB); an engineer saves the cell as a job,
// loads, deletes, and imports a job file; anyone exports one (a download
// of the job file, fetched in pieces with JOB EXPORT). An import sends the
// file in pieces (JOB IMPORT), each through the same checked, recorded
// command route as every line; the app checks the whole file before it
// stores it.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  // docs/PROTOCOL.md, "Jobs": names, the largest file, the import's pieces.
  const kNamePattern = /^[A-Za-z0-9_\-][A-Za-z0-9_.\-]{0,63}$/;
  const kMaxJobBytes = 64 * 1024 * 1024;
  const kImportPiece = 2880;

  function setBusy(text) {
    $("jobs-progress").textContent = text || "";
  }

  function nameOrComplain(id) {
    const name = String($(id).value).trim();
    if (kNamePattern.test(name)) return name;
    ps.show("jobs-reply", "(" + (name || "no name") + ")",
            "ERROR a job name is 1 to 64 of A-Z a-z 0-9 _ . -, not starting with '.'");
    return null;
  }

  async function refresh() {
    const current = await ps.command("JOB");
    $("jobs-current").textContent = current.startsWith("OK ") ? current.slice(3) : "-";
    const reply = await ps.command("JOB LIST");
    const body = $("jobs-list").querySelector("tbody");
    body.textContent = "";
    if (!reply.startsWith("OK ")) {
      ps.show("jobs-reply", "JOB LIST", reply);
      return reply;
    }
    const names = reply.split(/\s+/).slice(2);
    for (const name of names) {
      const tr = document.createElement("tr");
      tr.dataset.job = name;
      const td = document.createElement("td");
      td.textContent = name + (name === $("jobs-current").textContent ? "  (in force)" : "");
      tr.appendChild(td);
      const actions = document.createElement("td");
      for (const [label, action, engineer] of [["Load", load, true], ["Export", exportJob, false],
                                               ["Delete", remove, true]]) {
        const b = document.createElement("button");
        b.type = "button";
        b.textContent = label;
        b.className = "job-" + label.toLowerCase() + (engineer ? " engineer-only" : "");
        b.addEventListener("click", () => action(name));
        actions.appendChild(b);
      }
      tr.appendChild(actions);
      body.appendChild(tr);
    }
    return reply;
  }
  ps.refreshJobs = refresh;

  async function save() {
    const name = nameOrComplain("jobs-name");
    if (!name) return null;
    const names = Array.from($("jobs-list").querySelectorAll("tr[data-job]")).map((r) => r.dataset.job);
    if (names.includes(name) && !window.confirm("Replace job " + name + " with the cell as it is now?"))
      return null;
    const reply = await ps.command("JOB SAVE " + name);
    ps.show("jobs-reply", "JOB SAVE " + name, reply);
    await refresh();
    return reply;
  }

  async function load(name) {
    const reply = await ps.command("JOB LOAD " + name);
    ps.show("jobs-reply", "JOB LOAD " + name, reply);
    await refresh();
    return reply;
  }

  async function remove(name) {
    if (!window.confirm("Delete job " + name + "? (The cell keeps what it runs.)")) return null;
    const reply = await ps.command("JOB DELETE " + name);
    ps.show("jobs-reply", "JOB DELETE " + name, reply);
    await refresh();
    return reply;
  }

  function fromBase64(text) {
    const raw = atob(text);
    const bytes = new Uint8Array(raw.length);
    for (let i = 0; i < raw.length; ++i) bytes[i] = raw.charCodeAt(i);
    return bytes;
  }

  function toBase64(bytes) {
    let raw = "";
    for (let i = 0; i < bytes.length; ++i) raw += String.fromCharCode(bytes[i]);
    return btoa(raw);
  }

  // The job file as bytes, fetched in pieces; null (and the reply shown)
  // on an error.
  async function fetchJob(name) {
    const pieces = [];
    let received = 0;
    for (;;) {
      const line = "JOB EXPORT " + name + " " + received;
      const reply = await ps.command(line);
      const f = reply.split(" ");
      if (f[0] !== "OK" || f.length < 4) {
        ps.show("jobs-reply", line, reply);
        return null;
      }
      const total = parseInt(f[1], 10);
      const piece = fromBase64(f[3]);
      pieces.push(piece);
      received += piece.length;
      setBusy("export " + name + ": " + received + " of " + total + " bytes");
      if (received >= total || piece.length === 0) break;
    }
    return new Blob(pieces, { type: "application/json" });
  }

  async function exportJob(name) {
    const blob = await fetchJob(name);
    setBusy("");
    if (!blob) return null;
    ps.lastExport = blob;  // for tests: what the download holds
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name + ".job";
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
    ps.show("jobs-reply", "export " + name, "OK " + blob.size + " bytes: " + name + ".job");
    return blob;
  }
  ps.exportJob = exportJob;

  // Sends `bytes` as job `name`: the last piece's reply (OK when stored).
  async function importBytes(name, bytes) {
    if (bytes.length > kMaxJobBytes) return "ERROR a job file is at most 64 MiB";
    if (bytes.length === 0) return "ERROR the file is empty";
    let reply = "";
    for (let at = 0; at < bytes.length; at += kImportPiece) {
      const piece = bytes.subarray(at, Math.min(bytes.length, at + kImportPiece));
      reply = await ps.command("JOB IMPORT " + name + " " + at + " " + bytes.length + " " + toBase64(piece));
      setBusy("import " + name + ": " + Math.min(bytes.length, at + kImportPiece) + " of " + bytes.length + " bytes");
      if (!reply.startsWith("MORE ")) break;
    }
    setBusy("");
    return reply;
  }
  ps.importJobBytes = importBytes;

  async function importFile() {
    const file = $("jobs-file").files[0];
    if (!file) return null;
    // The file's own name without .job, unless a name is typed.
    const typed = String($("jobs-import-name").value).trim();
    const name = typed || file.name.replace(/\.job$/, "");
    if (!kNamePattern.test(name)) {
      ps.show("jobs-reply", "import " + file.name, "ERROR give the job a name: 1 to 64 of A-Z a-z 0-9 _ . -");
      return null;
    }
    if (file.size > kMaxJobBytes) {
      ps.show("jobs-reply", "import " + file.name, "ERROR a job file is at most 64 MiB");
      return null;
    }
    const reply = await importBytes(name, new Uint8Array(await file.arrayBuffer()));
    ps.show("jobs-reply", "import " + file.name + " as " + name, reply);
    $("jobs-file").value = "";
    await refresh();
    return reply;
  }

  document.addEventListener("DOMContentLoaded", () => {
    $("jobs-save").addEventListener("click", save);
    $("jobs-refresh").addEventListener("click", refresh);
    $("jobs-import").addEventListener("click", importFile);
    ps.on("tab", (tab) => { if (tab === "jobs") refresh(); });
    ps.on("camera", () => { if (ps.tab === "jobs") refresh(); });
  });
})();

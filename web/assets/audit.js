// PickSight web HMI, Audit panel: the newest records of the audit trail
// (GET /api/audit: who changed what, from where, with what reply, before
// and after), for engineers and admins; admins also export the whole trail.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;

  // A value of a record as one short text.
  // Objects as "key=value key=value".
  function text(v) {
    if (v === undefined || v === null) return "";
    if (typeof v !== "object" || Array.isArray(v)) return typeof v === "string" ? v : JSON.stringify(v);
    return Object.entries(v).map(([k, x]) => k + "=" + (typeof x === "object" ? JSON.stringify(x) : x)).join(" ");
  }

  function argumentsText(rec) {
    const a = rec.arguments;
    if (a && typeof a === "object" && typeof a.line === "string") return a.line;
    return text(a);
  }

  function outcomeText(rec) {
    let out = rec.outcome || "";
    if (rec.code) out += " " + rec.code;
    if (rec.reply) out += ": " + rec.reply;
    return out;
  }

  function changeText(rec) {
    if (rec.before === undefined && rec.after === undefined) return "";
    return text(rec.before) + " \u2192 " + text(rec.after);
  }

  async function refresh() {
    const limit = Math.min(1000, Math.max(1, Math.floor(Number($("audit-limit").value)) || 100));
    const r = await ps.get("/api/audit?limit=" + limit);
    const tbody = $("audit-list").querySelector("tbody");
    tbody.textContent = "";
    if (!r.ok) { $("audit-notes").textContent = r.body.error; return; }
    for (const rec of r.body.records) {
      const who = (rec.user || "-") + (rec.role ? " (" + rec.role + ")" : "");
      const row = ps.tableRow(tbody, [
        String(rec.time || "").replace("T", " ").replace("Z", ""), who, rec.address || "",
        rec.action || "", rec.target || "", argumentsText(rec), outcomeText(rec), changeText(rec),
      ]);
      row.classList.add("audit-" + (rec.outcome || "none"));
    }
    $("audit-file").textContent = r.body.file ? "file " + r.body.file : "kept in memory (no --audit-file)";
    $("audit-notes").textContent = (r.body.notes || []).join("\n");
  }
  ps.refreshAudit = refresh;

  ps.on("tab", (tab) => {
    // The trail's columns need a wider panel than the others.
    $("panels").classList.toggle("wide", tab === "audit");
    if (tab === "audit") refresh();
  });
  document.addEventListener("DOMContentLoaded", () => {
    $("audit-refresh").addEventListener("click", refresh);
  });
})();

// PickSight web HMI, Users panel (admins only): the users and their roles,
// adding one, changing a role, resetting a password, removing one. The
// server decides (an admin's session; the last admin can neither lose the
// role nor be removed) and records each change in the audit trail; the
// panel shows its answer.
"use strict";

(function () {
  const ps = window.picksight;
  const $ = ps.$;
  const ROLES = ["operator", "engineer", "admin"];

  function roleSelect(value) {
    const select = document.createElement("select");
    for (const r of ROLES) {
      const o = document.createElement("option");
      o.value = r; o.textContent = r;
      select.appendChild(o);
    }
    select.value = value;
    return select;
  }

  function button(text, onClick) {
    const b = document.createElement("button");
    b.type = "button";
    b.textContent = text;
    b.addEventListener("click", onClick);
    return b;
  }

  // Sends one change; refreshes the list, then shows the server's answer:
  // once the answer shows, the rows are the new ones (a Delete armed on a
  // row the refresh then replaced would silently need a third click). A
  // change to the admin's own user ends the admin's session too (the page
  // then asks for a login).
  async function change(what, url, body) {
    const r = await ps.post(url, body);
    if (r.ok || r.status !== 401) await refresh();
    ps.show("users-reply", what, r.ok ? "OK" : "ERROR " + r.body.error);
    return r;
  }

  function userUrl(name, action) {
    return "/api/users/" + encodeURIComponent(name) + "/" + action;
  }

  function row(tbody, user) {
    const tr = document.createElement("tr");
    tr.dataset.user = user.name;
    const name = document.createElement("td");
    name.textContent = user.name;
    if (ps.user && user.name === ps.user.user) name.textContent += " (you)";
    tr.appendChild(name);

    const role = document.createElement("td");
    const select = roleSelect(user.role);
    select.className = "user-role";
    role.append(select, button("Set role", () =>
      change("role of " + user.name + " = " + select.value, userUrl(user.name, "role"), { role: select.value })));
    tr.appendChild(role);

    const password = document.createElement("td");
    const input = document.createElement("input");
    input.type = "password";
    input.className = "user-password";
    input.autocomplete = "new-password";
    input.placeholder = "new password";
    password.append(input, button("Reset", () => {
      const value = input.value;
      input.value = "";
      change("password of " + user.name, userUrl(user.name, "password"), { password: value });
    }));
    tr.appendChild(password);

    // Two clicks remove a user: the first arms the button for 5 s (a
    // dialog would stop the page's own traffic while it is open).
    const remove = document.createElement("td");
    const del = button("Delete", () => {
      if (!del.classList.contains("armed")) {
        del.classList.add("armed");
        del.textContent = "Really delete?";
        setTimeout(() => { del.classList.remove("armed"); del.textContent = "Delete"; }, 5000);
        return;
      }
      change("delete " + user.name, userUrl(user.name, "delete"));
    });
    del.className = "user-delete";
    remove.appendChild(del);
    tr.appendChild(remove);
    tbody.appendChild(tr);
  }

  async function refresh() {
    const tbody = $("users-list").querySelector("tbody");
    const r = await ps.get("/api/users");
    tbody.textContent = "";
    if (!r.ok || !Array.isArray(r.body)) {
      ps.show("users-reply", "list users", "ERROR " + r.body.error);
      return;
    }
    for (const user of r.body) row(tbody, user);
  }
  ps.refreshUsers = refresh;

  async function add() {
    const name = $("user-add-name").value.trim();
    const body = { name, role: $("user-add-role").value, password: $("user-add-password").value, new: true };
    $("user-add-password").value = "";
    const r = await change("add " + name + " (" + body.role + ")", "/api/users", body);
    if (r.ok) $("user-add-name").value = "";
  }

  ps.on("tab", (tab) => { if (tab === "users") refresh(); });
  document.addEventListener("DOMContentLoaded", () => {
    $("user-add-form").addEventListener("submit", (e) => { e.preventDefault(); add(); });
    $("users-refresh").addEventListener("click", refresh);
  });
})();

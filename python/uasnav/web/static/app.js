// uasnav mission planner: small enhancements only; every page works without this script.
(function () {
  "use strict";
  document.documentElement.classList.add("js");

  // Print buttons.
  document.querySelectorAll("[data-print]").forEach(function (b) {
    b.addEventListener("click", function () { window.print(); });
  });

  // Numeric fields: say what is wrong beside the field as soon as it is left (the server
  // checks again and has the last word).
  document.querySelectorAll("input[data-kind]").forEach(function (input) {
    var msg = document.getElementById("e-" + input.name);
    input.addEventListener("change", function () {
      var t = input.value.trim(), err = "";
      if (t !== "") {
        var x = Number(t);
        var lo = input.dataset.min, hi = input.dataset.max, open = input.dataset.minOpen === "1";
        if (!isFinite(x) || isNaN(x)) err = input.name + ": " + JSON.stringify(t) + " is not a number";
        else if (input.dataset.kind === "int" && !Number.isInteger(x)) err = input.name + ": expected an integer";
        else if (lo !== undefined && (open ? x <= Number(lo) : x < Number(lo))) err = input.name + ": " + t + " is not " + (open ? ">" : ">=") + " " + Number(lo);
        else if (hi !== undefined && x > Number(hi)) err = input.name + ": " + t + " is not <= " + Number(hi);
      }
      if (msg) msg.textContent = err;
      input.closest(".field").classList.toggle("invalid", err !== "");
      if (err) input.setAttribute("aria-invalid", "true"); else input.removeAttribute("aria-invalid");
    });
  });

  // Sortable tables: click (or Enter on) a header to sort; numbers by data-value.
  document.querySelectorAll("table.sortable").forEach(function (table) {
    var heads = table.tHead ? table.tHead.rows[0].cells : [];
    Array.prototype.forEach.call(heads, function (th, col) {
      if (th.querySelector("a")) return; // server-sorted tables keep their links
      th.dataset.sort = "";
      th.tabIndex = 0;
      th.setAttribute("aria-sort", "none");
      var sort = function () {
        var asc = th.getAttribute("aria-sort") !== "ascending";
        Array.prototype.forEach.call(heads, function (h) { if (h.dataset.sort !== undefined) h.setAttribute("aria-sort", "none"); });
        th.setAttribute("aria-sort", asc ? "ascending" : "descending");
        var body = table.tBodies[0], rows = Array.prototype.slice.call(body.rows);
        var val = function (r) {
          var c = r.cells[col], v = c.dataset.value !== undefined ? c.dataset.value : c.textContent.trim();
          var x = parseFloat(v);
          return th.dataset.type === "num" && !isNaN(x) ? x : v.toLowerCase();
        };
        rows.sort(function (a, b) { var x = val(a), y = val(b); return (x < y ? -1 : x > y ? 1 : 0) * (asc ? 1 : -1); });
        rows.forEach(function (r) { body.appendChild(r); });
      };
      th.addEventListener("click", sort);
      th.addEventListener("keydown", function (e) { if (e.key === "Enter" || e.key === " ") { e.preventDefault(); sort(); } });
    });
  });

  // Instant filter of a table by the search box (the form still filters on the server).
  document.querySelectorAll("input[data-filter]").forEach(function (input) {
    var table = document.querySelector(input.dataset.filter), count = document.getElementById("count");
    if (!table) return;
    input.addEventListener("input", function () {
      var words = input.value.toLowerCase().split(/\s+/).filter(Boolean), n = 0;
      Array.prototype.forEach.call(table.tBodies[0].rows, function (r) {
        var text = r.textContent.toLowerCase();
        var show = words.every(function (w) { return text.indexOf(w) >= 0; });
        r.hidden = !show;
        if (show) n++;
      });
      if (count) count.textContent = n + " rows";
    });
  });
})();

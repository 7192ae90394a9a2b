// uasnav mission planner: small enhancements only; every page works without this script.
(function () {
  "use strict";
  document.documentElement.classList.add("js");

  // After a run, the answer (or the list of fields to correct) takes the focus, so a keyboard
  // or screen-reader user lands on it rather than at the top of the form. The script lands the
  // page itself, once, and only if nothing has been focused yet: the forms then post to a URL
  // without the "#results" fragment they carry for browsers without scripts, whose own
  // fragment focus comes at a time of the browser's choosing (after the page's render-blocking
  // resources) and would take the focus back from whatever the user had moved it to.
  document.querySelectorAll("form[data-lands]").forEach(function (form) {
    form.setAttribute("action", form.getAttribute("action").split("#")[0]);
  });
  var landing = document.getElementById("form-error") || document.getElementById("results") ||
    document.getElementById("prediction");
  var untouched = !document.activeElement || document.activeElement === document.body;
  if (landing && untouched) {
    if (!landing.hasAttribute("tabindex")) landing.tabIndex = -1;
    landing.focus();
  }

  // Uploads: a file over the server's limit is refused here, beside its field, with the form
  // kept (the server would refuse the whole request).
  document.querySelectorAll("form[data-max-upload]").forEach(function (form) {
    var limit = Number(form.dataset.maxUpload);
    var check = function (input) {
      var msg = document.getElementById("e-" + input.name) || document.getElementById("te-" + input.name);
      var size = 0;
      Array.prototype.forEach.call(input.files || [], function (f) { size += f.size; });
      var err = size > limit ? input.name + ": this file is " + (size / 1048576).toFixed(1) +
        " MB, over the " + Math.round(limit / 1048576) + " MB limit: choose a smaller file" : "";
      if (msg) msg.textContent = err;
      input.closest(".field").classList.toggle("invalid", err !== "");
      if (err) input.setAttribute("aria-invalid", "true"); else input.removeAttribute("aria-invalid");
      return err === "";
    };
    var files = form.querySelectorAll("input[type=file]");
    files.forEach(function (input) { input.addEventListener("change", function () { check(input); }); });
    form.addEventListener("submit", function (e) {
      var bad = null, total = 0;
      files.forEach(function (input) {
        if (!check(input) && !bad) bad = input;
        Array.prototype.forEach.call(input.files || [], function (f) { total += f.size; });
      });
      if (!bad && total > limit && files.length) { bad = files[0]; check(bad); }
      if (bad) { e.preventDefault(); bad.focus(); }
    });
  });

  // Wide tables: the "scroll sideways" cue only when the table is wider than its box.
  var cues = function () {
    document.querySelectorAll(".scroll").forEach(function (box) {
      var cue = box.previousElementSibling;
      if (cue && cue.classList.contains("scroll-cue")) {
        cue.classList.toggle("shown", box.scrollWidth > box.clientWidth + 1);
      }
    });
  };
  cues();
  window.addEventListener("resize", cues);

  // The offline map: a click or tap places the take-off point or the pilot's position (the
  // latitude,longitude fields under "Advanced" stay the keyboard's way); the next run uses them.
  // The drawing's georeference is on the svg (uasnav.web.area_map).
  var map = document.querySelector("svg.map[data-view]"), chooser = document.getElementById("map-set");
  if (map && chooser) {
    chooser.hidden = false;
    var nums = function (s) { return s.split(",").map(Number); };
    var origin = nums(map.dataset.origin), perDeg = nums(map.dataset.mPerDeg), view = nums(map.dataset.view);
    var status = document.getElementById("map-status");
    var NS = "http://www.w3.org/2000/svg";
    var marker = function (which, x, y) {
      var g = map.querySelector("g.pt." + which);
      if (!g) {
        g = document.createElementNS(NS, "g");
        g.setAttribute("class", "pt " + which);
        g.appendChild(document.createElementNS(NS, "circle")).setAttribute("r", "6");
        g.appendChild(document.createElementNS(NS, "text")).textContent = which === "pilot" ? "pilot" : "take-off";
        map.insertBefore(g, map.querySelector("g.scale"));
      }
      g.querySelector("circle").setAttribute("cx", x.toFixed(1));
      g.querySelector("circle").setAttribute("cy", y.toFixed(1));
      g.querySelector("text").setAttribute("x", (x + 9).toFixed(1));
      g.querySelector("text").setAttribute("y", (y + 4).toFixed(1));
    };
    map.addEventListener("click", function (ev) {
      var pt = map.createSVGPoint();
      pt.x = ev.clientX; pt.y = ev.clientY;
      var p = pt.matrixTransform(map.getScreenCTM().inverse());
      var east = view[3] + (p.x - view[0]) / view[2], north = view[4] - (p.y - view[1]) / view[2];
      var lat = origin[0] + north / perDeg[0], lon = origin[1] + east / perDeg[1];
      var which = chooser.querySelector("input[name=map-point]:checked").value;
      var field = document.getElementById("f-" + which);
      if (!field) return;
      field.value = lat.toFixed(6) + "," + lon.toFixed(6);
      marker(which, p.x, p.y);
      status.textContent = (which === "pilot" ? "Your position" : "Take-off point") + " set to " +
        field.value + ". Run again to plan from it.";
    });
  }

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

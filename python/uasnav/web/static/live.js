// The /live page: server-sent snapshots (10 Hz) drawn on an offline SVG map (an
// equirectangular projection around the volumes' centre; no map tiles).
"use strict";
(function () {
  const SVG = "http://www.w3.org/2000/svg";
  const map = document.getElementById("live-map");
  const status = document.getElementById("live-status");
  const tbody = document.querySelector("#live-vehicles tbody");
  const navEl = document.getElementById("live-nav");
  const eventsEl = document.getElementById("live-events");
  let proj = null;
  const trails = {};

  function projection(points) {
    let la0 = Infinity, la1 = -Infinity, lo0 = Infinity, lo1 = -Infinity;
    for (const [la, lo] of points) { la0 = Math.min(la0, la); la1 = Math.max(la1, la); lo0 = Math.min(lo0, lo); lo1 = Math.max(lo1, lo); }
    const lat = (la0 + la1) / 2, lon = (lo0 + lo1) / 2, k = Math.cos(lat * Math.PI / 180);
    const w = Math.max((lo1 - lo0) * k, la1 - la0, 1e-4) * 1.3;
    return (la, lo) => [300 + ((lo - lon) * k / w) * 600, 200 - ((la - lat) / w) * 600];
  }
  function el(name, attrs) {
    const e = document.createElementNS(SVG, name);
    for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
    return e;
  }
  function circle(c, r) { // a circle volume as 32 points (metres to degrees)
    const out = [];
    for (let i = 0; i < 32; i++) {
      const a = 2 * Math.PI * i / 32;
      out.push([c[0] + r * Math.cos(a) / 111320, c[1] + r * Math.sin(a) / (111320 * Math.cos(c[0] * Math.PI / 180))]);
    }
    return out;
  }
  fetch("/live/intents").then(r => r.json()).then(d => {
    const polys = d.volumes.map(v => v.radius_m === null ? v.latlon : circle(v.latlon[0], v.radius_m));
    if (!polys.length) return;
    proj = projection(polys.flat());
    for (const p of polys) {
      map.appendChild(el("polygon", {points: p.map(q => proj(q[0], q[1]).join(",")).join(" "), fill: "#cfe3ff", "fill-opacity": "0.5", stroke: "#3b6fb6"}));
    }
  });
  function dot(id, la, lo, color) {
    let c = document.getElementById(id);
    if (!c) { c = el("circle", {id: id, r: "5", fill: color, stroke: "#000"}); map.appendChild(c); }
    const [x, y] = proj(la, lo);
    c.setAttribute("cx", x); c.setAttribute("cy", y);
  }
  function fmt(x, d) { return x === null || x === undefined ? "–" : Number(x).toFixed(d); }
  const source = new EventSource("/live/events");
  source.onmessage = (m) => {
    const s = JSON.parse(m.data);
    if (s.error) { status.textContent = s.error; }
    else { status.textContent = `${s.messages} messages received`; }
    tbody.replaceChildren();
    for (const [id, v] of Object.entries(s.vehicles || {})) {
      const tr = document.createElement("tr");
      tr.dataset.vehicle = id;
      const cells = [id, v.state || "–", v.lat === undefined ? "–" : `${fmt(v.lat, 6)}, ${fmt(v.lon, 6)}`,
        v.margin_m === undefined || v.margin_m === null ? "–" : `${fmt(v.margin_m, 1)} m`, (v.reason || "") + (v.telemetry === "telemetry_lost" ? " · telemetry lost" : "")];
      for (const c of cells) { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); }
      tr.children[1].className = "state-" + (v.state || "none").toLowerCase();
      tbody.appendChild(tr);
      if (proj && v.lat !== undefined) {
        const t = trails[id] = trails[id] || el("polyline", {fill: "none", stroke: "#b33", "stroke-width": "1.5"});
        if (!t.parentNode) map.appendChild(t);
        const [x, y] = proj(v.lat, v.lon);
        t.setAttribute("points", ((t.getAttribute("points") || "") + ` ${x},${y}`).trim().split(" ").slice(-600).join(" "));
        dot("veh-" + id, v.lat, v.lon, v.state === "Activated" ? "#2a2" : "#d22");
      }
    }
    if (s.nav) {
      navEl.textContent = `t ${fmt(s.nav.t_boot_s, 2)} s · ${fmt(s.nav.lat, 7)}, ${fmt(s.nav.lon, 7)}, ${fmt(s.nav.alt_w84_m, 1)} m W84 · HPL ${fmt(s.nav.hpl_m, 1)} m · VPL ${fmt(s.nav.vpl_m, 1)} m`;
      if (proj) dot("nav-solution", s.nav.lat, s.nav.lon, "#fa0");
    }
    eventsEl.replaceChildren();
    for (const e of (s.events || []).slice().reverse()) {
      const li = document.createElement("li");
      li.textContent = `${e.time_utc || ""} vehicle ${e.vehicle}: ${e.event === "state" ? e.state : e.event} — ${e.reason}`;
      eventsEl.appendChild(li);
    }
  };
})();

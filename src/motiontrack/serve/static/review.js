// motiontrack review: a day of stored events as a timeline per camera; click an event for its
// snapshot and clip. Plain browser JavaScript; it talks only to /api/events/* of `motiontrack serve`.
"use strict";

const TOKEN = new URLSearchParams(location.search).get("token");
const PAGE = 1000;                          // the most events one search returns
const COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf"];
const SVG = "http://www.w3.org/2000/svg";

function withToken(path) {
  if (!TOKEN) return path;
  return path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(TOKEN);
}

async function api(path) {
  const response = await fetch(withToken(path), { cache: "no-store" });
  const body = await response.json();
  if (!response.ok) throw new Error(body.error || response.statusText);
  return body;
}

const $ = (id) => document.getElementById(id);

function dayBounds(value) {
  // local midnight to the next, in epoch seconds
  const [y, m, d] = value.split("-").map(Number);
  const start = new Date(y, m - 1, d).getTime() / 1000;
  return [start, new Date(y, m - 1, d + 1).getTime() / 1000];
}

function isoDay(epoch) {
  const t = new Date(epoch * 1000);
  const pad = (n) => String(n).padStart(2, "0");
  return `${t.getFullYear()}-${pad(t.getMonth() + 1)}-${pad(t.getDate())}`;
}

function query(extra = {}) {
  const q = new URLSearchParams();
  const [since, until] = dayBounds($("day").value);
  q.set("since", new Date(since * 1000).toISOString());
  q.set("until", new Date(until * 1000).toISOString());
  for (const key of ["camera", "type", "rule"]) if ($(key).value) q.set(key, $(key).value);
  for (const [k, v] of Object.entries(extra)) q.set(k, v);
  return q.toString();
}

async function dayEvents() {
  // every event of the day, a page at a time
  const events = [];
  for (let offset = 0; ; offset += PAGE) {
    const page = await api("api/events/search?" + query({ limit: PAGE, offset }));
    events.push(...page.events);
    if (events.length >= page.total || !page.events.length) return events;
  }
}

function fillSelect(select, values) {
  const keep = select.value;
  select.replaceChildren(new Option("all", ""));
  for (const v of [...values].sort()) select.add(new Option(v, v));
  select.value = values.has(keep) ? keep : "";
}

function drawTimeline(events, [since, until]) {
  const box = $("timeline");
  box.replaceChildren();
  const cameras = [...new Set(events.map((e) => e.camera))].sort();
  const types = [...new Set(events.map((e) => e.type))].sort();
  const width = Math.max(box.clientWidth, 600), row = 34, left = 110;
  const svg = document.createElementNS(SVG, "svg");
  svg.setAttribute("width", width);
  svg.setAttribute("height", row * (cameras.length + 1));
  const x = (t) => left + ((t - since) / (until - since)) * (width - left - 10);
  for (let h = 0; h <= 24; h += 3) {
    const tick = document.createElementNS(SVG, "text");
    tick.setAttribute("x", x(since + h * 3600));
    tick.setAttribute("y", row * cameras.length + 20);
    tick.setAttribute("class", "tick");
    tick.textContent = `${String(h).padStart(2, "0")}:00`;
    svg.appendChild(tick);
  }
  cameras.forEach((camera, i) => {
    const label = document.createElementNS(SVG, "text");
    label.setAttribute("x", 4);
    label.setAttribute("y", row * i + 21);
    label.textContent = camera;
    svg.appendChild(label);
    const line = document.createElementNS(SVG, "line");
    line.setAttribute("x1", left); line.setAttribute("x2", width - 10);
    line.setAttribute("y1", row * i + 17); line.setAttribute("y2", row * i + 17);
    line.setAttribute("class", "lane");
    svg.appendChild(line);
  });
  for (const e of events) {
    const mark = document.createElementNS(SVG, "circle");
    mark.setAttribute("cx", x(e.end));
    mark.setAttribute("cy", row * cameras.indexOf(e.camera) + 17);
    mark.setAttribute("r", 6);
    mark.setAttribute("fill", COLOURS[types.indexOf(e.type) % COLOURS.length]);
    mark.setAttribute("data-testid", "event-mark");
    mark.setAttribute("data-id", e.id);
    mark.setAttribute("tabindex", "0");
    const title = document.createElementNS(SVG, "title");
    title.textContent = `${e.type} ${e.rule || ""} ${new Date(e.end * 1000).toLocaleTimeString()}`;
    mark.appendChild(title);
    mark.addEventListener("click", () => showEvent(e));
    mark.addEventListener("keydown", (k) => { if (k.key === "Enter") showEvent(e); });
    svg.appendChild(mark);
  }
  box.appendChild(svg);
}

function showEvent(e) {
  $("detail").hidden = false;
  $("detail-title").textContent =
    `${e.type} ${e.rule ? "at " + e.rule : ""} — ${e.camera}, ${new Date(e.end * 1000).toLocaleString()}`;
  const base = `api/events/${e.id}/`;
  for (const [id, file, present] of [["snapshot", "snapshot.jpg", e.snapshot], ["object", "object.jpg", e.snapshot],
                                     ["clip", "clip.mjpg", e.clip]]) {
    $(id).hidden = !present;
    if (present) $(id).src = withToken(base + file);
    else $(id).removeAttribute("src");
  }
  $("clip-file").href = withToken(base + "clip.avi");
  $("detail-json").textContent = JSON.stringify(e.event, null, 1);
}

async function drawTotals() {
  const { totals } = await api("api/events/totals?bin=hour&" + query());
  const body = $("totals").tBodies[0];
  body.replaceChildren();
  if (new Set(totals.map((t) => t.camera)).size > 1) {
    // and over every camera
    const every = new Map();
    for (const t of totals) {
      const key = `${t.start}\u0000${t.type}`;
      every.set(key, (every.get(key) || 0) + t.count);
    }
    for (const [key, count] of [...every.entries()].sort()) {
      const [start, type] = key.split("\u0000");
      totals.push({ camera: "(all)", start: Number(start), type, count });
    }
  }
  for (const t of totals) {
    const tr = body.insertRow();
    for (const v of [t.camera, new Date(t.start * 1000).toLocaleString(), t.type, t.count]) tr.insertCell().textContent = v;
  }
}

async function refresh() {
  try {
    const events = await dayEvents();
    drawTimeline(events, dayBounds($("day").value));
    await drawTotals();
    $("status").textContent = `${events.length} event${events.length === 1 ? "" : "s"} on ${$("day").value}`;
    return events;
  } catch (err) {
    $("status").textContent = "error: " + err.message;
    return [];
  }
}

async function start() {
  // the day of the newest event (or today), and the filters' choices from the whole store
  const newest = await api("api/events/search?limit=" + PAGE);
  $("day").value = isoDay(newest.events.length ? newest.events[0].end : Date.now() / 1000);
  fillSelect($("camera"), new Set(newest.events.map((e) => e.camera)));
  fillSelect($("type"), new Set(newest.events.map((e) => e.type)));
  fillSelect($("rule"), new Set(newest.events.map((e) => e.rule).filter(Boolean)));
  for (const id of ["day", "camera", "type", "rule"]) $(id).addEventListener("change", refresh);
  await refresh();
}

start();

// motiontrack live: camera tiles, event feed, counts and the line/zone editor.
// Plain browser JavaScript, no build step; it talks only to the JSON API of `motiontrack serve`.
"use strict";

const TOKEN = new URLSearchParams(location.search).get("token");
const FEED_MAX = 200;           // feed lines kept on the page (newest first)
const POLL_MS = 1000;           // /api/cameras
const COUNTS_POLL_MS = 5000;    // /api/cameras/{name}/counts: the server's totals win over local sums

// ---------------------------------------------------------------- requests

// Every request carries the token: images and EventSource cannot set headers, so it goes in the query.
function withToken(path) {
  if (!TOKEN) return path;
  return path + (path.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(TOKEN);
}

function cameraPath(name, rest) {
  return "api/cameras/" + encodeURIComponent(name) + "/" + rest;
}

async function api(path, options = {}) {
  const response = await fetch(withToken(path), { cache: "no-store", ...options });
  let body = null;
  const type = response.headers.get("content-type") || "";
  if (type.includes("json")) body = await response.json();
  else body = await response.text();
  if (!response.ok) {
    const text = body && typeof body === "object" && body.error ? body.error : String(body || response.statusText);
    const err = new Error(text);
    err.status = response.status;
    throw err;
  }
  return body;
}

// ---------------------------------------------------------------- small DOM helpers

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "text") node.textContent = v;
    else if (k.startsWith("on")) node.addEventListener(k.slice(2), v);
    else node.setAttribute(k, v);
  }
  for (const c of children) node.append(c);
  return node;
}

function fmt(v, digits) {
  if (v === null || v === undefined || Number.isNaN(v)) return "–";
  return typeof v === "number" && digits !== undefined ? v.toFixed(digits) : String(v);
}

// ---------------------------------------------------------------- camera tiles

const tiles = new Map();   // name -> {img, fields}

function streamUrl(name) {
  // a changing query makes the browser open a fresh stream after an error
  return withToken(cameraPath(name, "stream.mjpg") + "?n=" + Date.now());
}

function snapshotUrl(name) {
  return withToken(cameraPath(name, "snapshot.jpg") + "?n=" + Date.now());
}

function keepStreaming(img, name) {
  // a stream ends when its camera restarts or the server drops a slow viewer: reopen it
  img.addEventListener("error", () => setTimeout(() => { img.src = streamUrl(name); }, 1000));
}

function makeTile(cam) {
  const name = cam.name;
  const img = el("img", {
    "data-testid": "camera-img-" + name,
    alt: "Live annotated picture of camera " + name,
  });
  keepStreaming(img, name);
  img.src = streamUrl(name);
  const fields = {};
  const stats = el("dl", { class: "stats" });
  for (const [key, label] of [["status", "status"], ["fps", "fps"], ["frames", "frames"], ["reconnects", "reconnects"], ["tracks", "tracks"]]) {
    fields[key] = el("dd", { "data-testid": "camera-" + key + "-" + name });
    stats.append(el("dt", { text: label }), fields[key]);
  }
  // a scene file the camera cannot apply (a hand edit with a mistake): the camera's message
  const sceneError = el("p", { class: "error scene-error", role: "alert", "data-testid": "camera-scene-error-" + name });
  sceneError.hidden = true;
  const tile = el("article", { class: "tile", "data-testid": "camera-tile-" + name, "aria-label": "Camera " + name },
    el("h3", { text: name }), el("div", { class: "picture" }, img), stats, sceneError);
  document.getElementById("cameras").append(tile);
  return { tile, img, fields, sceneError };
}

function updateTile(cam) {
  let t = tiles.get(cam.name);
  if (!t) {
    t = makeTile(cam);
    tiles.set(cam.name, t);
  }
  t.fields.status.textContent = fmt(cam.status);
  t.fields.status.dataset.status = cam.status || "";
  t.fields.fps.textContent = fmt(cam.fps, 1);
  t.fields.frames.textContent = fmt(cam.frames);
  t.fields.reconnects.textContent = fmt(cam.reconnects);
  t.fields.tracks.textContent = trackList(cam.tracks);
  // a camera whose run has ended sends no more pictures, and a browser shows an MJPEG part only
  // once the next one begins: the tile shows the last picture as a still instead
  const ended = cam.status === "ended";
  if (ended !== Boolean(t.ended)) {
    t.ended = ended;
    t.img.src = ended ? snapshotUrl(cam.name) : streamUrl(cam.name);
  }
  t.sceneError.textContent = cam.scene_error ? "scene not applied: " + cam.scene_error : "";
  t.sceneError.hidden = !cam.scene_error;
}

let cameras = [];

async function pollCameras() {
  const conn = document.getElementById("connection");
  try {
    cameras = await api("api/cameras");
    for (const cam of cameras) {
      updateTile(cam);
      ensureCounts(cam.name);
    }
    editor.offerCameras(cameras);
    conn.textContent = "connected: " + cameras.length + " camera" + (cameras.length === 1 ? "" : "s");
    conn.dataset.state = "ok";
  } catch (err) {
    conn.textContent = "server unreachable: " + err.message;
    conn.dataset.state = "error";
  }
}

// ---------------------------------------------------------------- counts

const counts = new Map();   // camera -> {lines: {name: {in, out}}, zones: {name: {occupancy, entered}}}

function ensureCounts(name) {
  if (!counts.has(name)) {
    counts.set(name, { lines: {}, zones: {} });
    refreshCounts(name);
    backfillEvents(name);
  }
}

async function refreshCounts(name) {
  try {
    const c = await api(cameraPath(name, "counts"));
    counts.set(name, { lines: c.lines || {}, zones: c.zones || {} });
    renderCounts(name);
  } catch (err) {
    // the next poll tries again; the feed keeps the local sums going meanwhile
  }
}

// The feed's events move the counts at once; the periodic fetch brings them back to the server's totals.
function countEvent(ev) {
  const c = counts.get(ev.camera);
  if (!c) return;
  if (ev.type === "line_cross" && ev.line) {
    const l = c.lines[ev.line] || (c.lines[ev.line] = { in: 0, out: 0 });
    if (ev.direction === "in" || ev.direction === "out") l[ev.direction] += 1;
  } else if ((ev.type === "zone_enter" || ev.type === "zone_exit") && ev.zone) {
    const z = c.zones[ev.zone] || (c.zones[ev.zone] = { occupancy: 0, entered: 0 });
    if (ev.type === "zone_enter") { z.entered += 1; z.occupancy += 1; }
    else z.occupancy = Math.max(0, z.occupancy - 1);
  } else {
    return;
  }
  renderCounts(ev.camera);
}

function renderCounts(name) {
  const c = counts.get(name);
  const box = document.getElementById("counts");
  let table = box.querySelector(`[data-camera="${CSS.escape(name)}"]`);
  const body = el("tbody");
  for (const [line, v] of Object.entries(c.lines).sort()) {
    body.append(el("tr", { "data-testid": "count-line-" + name + "-" + line, "data-kind": "line", "data-name": line, "data-in": v.in, "data-out": v.out },
      el("th", { scope: "row", text: "line " + line }),
      el("td", { "data-field": "in", text: fmt(v.in) + " in" }),
      el("td", { "data-field": "out", text: fmt(v.out) + " out" })));
  }
  for (const [zone, v] of Object.entries(c.zones).sort()) {
    body.append(el("tr", { "data-testid": "count-zone-" + name + "-" + zone, "data-kind": "zone", "data-name": zone,
      "data-occupancy": v.occupancy, "data-entered": v.entered },
      el("th", { scope: "row", text: "zone " + zone }),
      el("td", { "data-field": "occupancy", text: fmt(v.occupancy) + " inside" }),
      el("td", { "data-field": "entered", text: fmt(v.entered) + " entered" })));
  }
  if (!body.children.length) body.append(el("tr", {}, el("td", { colspan: "3", text: "no lines or zones" })));
  const fresh = el("table", { "data-camera": name, "data-testid": "counts-" + name },
    el("caption", { text: name }), body);
  if (table) table.replaceWith(fresh);
  else box.append(fresh);
}

// each track of the latest frame with its class: "3 person · 7 vehicle"
function trackList(tracks) {
  if (!tracks || !tracks.length) return "none";
  return tracks.map((t) => t.class ? t.id + " " + t.class : String(t.id)).join(" · ");
}

// ---------------------------------------------------------------- event feed

function describe(ev) {
  const parts = [ev.type];
  if (ev.reason) parts.push(ev.reason);
  if (ev.line) parts.push(ev.line + (ev.direction ? " " + ev.direction : ""));
  if (ev.zone) parts.push(ev.zone);
  if (ev.track !== undefined) parts.push("track " + ev.track + (ev.label ? " (" + ev.label + ")" : ""));
  if (ev.dwell_s !== undefined) parts.push("dwell " + fmt(ev.dwell_s, 1) + " s");
  if (ev.duration_s !== undefined) parts.push(fmt(ev.duration_s, 1) + " s");
  return parts.join(" · ");
}

const shownEvents = new Set();   // "camera seq" of the events in the feed

function addEvent(ev, older = false) {
  const key = ev.camera + " " + ev.seq;
  if (shownEvents.has(key)) return false;
  shownEvents.add(key);
  const feed = document.getElementById("feed");
  const item = el("li", {
    "data-testid": "event",
    "data-camera": ev.camera,
    "data-seq": ev.seq,
    "data-type": ev.type,
    "data-frame": ev.frame,
    // when this page received it (ms since the epoch): the latency the feed shows
    "data-received-ms": Date.now(),
  },
  el("span", { class: "when", text: new Date().toLocaleTimeString() }),
  el("span", { class: "camera", text: ev.camera }),
  el("span", { class: "what", text: describe(ev) }),
  el("span", { class: "frame", text: "frame " + fmt(ev.frame) }));
  item.dataset.event = JSON.stringify(ev);
  if (older) feed.append(item);
  else feed.prepend(item);
  while (feed.children.length > FEED_MAX) feed.lastElementChild.remove();
  return true;
}

// The events a camera had before this page opened (a run that has ended, a page reloaded):
// kept by the server, shown below the ones that arrive live.
async function backfillEvents(name) {
  try {
    const kept = await api(cameraPath(name, "events"));
    for (const ev of kept.slice().reverse()) addEvent({ camera: name, ...ev }, true);
  } catch (err) {
    // the live stream still shows what comes next
  }
}

function listen() {
  const source = new EventSource(withToken("api/events"));
  source.onmessage = (msg) => {
    let ev;
    try { ev = JSON.parse(msg.data); } catch (err) { return; }
    if (!ev || !ev.camera) return;
    if (addEvent(ev)) countEvent(ev);
  };
  // EventSource reconnects by itself; nothing else to do on error
}

// ---------------------------------------------------------------- scene schema

// The editor checks the lines and zones it is about to send against the scene file's JSON Schema
// (api/schema/scene, draft 2020-12), so that a bad name or number is named at once; the server
// checks the scene again with everything a schema cannot say (unique names, simple polygons,
// metres through the calibration) and its answer is the one that counts. Only the keywords the
// export uses are understood; any other is ignored, which can let a scene through to the server,
// never refuse one the schema allows.

function jsonType(v) {
  if (v === null) return "null";
  if (Array.isArray(v)) return "array";
  if (typeof v === "number") return Number.isInteger(v) ? "integer" : "number";
  return typeof v;
}

const TYPE_WORDS = {
  object: "a table", array: "an array", string: "a string", number: "a number",
  integer: "a whole number", boolean: "true or false", null: "null",
};

function shown(v) {
  const text = JSON.stringify(v);
  return text === undefined ? String(v) : text.length > 40 ? text.slice(0, 37) + "..." : text;
}

function sameJson(a, b) {
  return JSON.stringify(a) === JSON.stringify(b);
}

// The first problem of `value` against `schema` as a phrase about `where` (a key path such as
// "points[1][0]"; "" for the value itself), or null when there is none.
function schemaProblem(schema, value, where) {
  if (schema === true || schema === undefined || schema === null) return null;
  const subject = (rest) => (where ? where + " " : "") + rest;
  if (schema === false) return subject("is not allowed");
  const type = jsonType(value);
  if (schema.type !== undefined) {
    const types = [].concat(schema.type);
    if (!types.some((t) => t === type || (t === "number" && type === "integer")))
      return subject("must be " + types.map((t) => TYPE_WORDS[t] || t).join(" or ") + ", got " + shown(value));
  }
  if ("const" in schema && !sameJson(value, schema.const))
    return subject("must be " + shown(schema.const) + ", got " + shown(value));
  if (Array.isArray(schema.enum) && !schema.enum.some((e) => sameJson(e, value)))
    return subject("must be one of " + schema.enum.map(shown).join(", ") + ", got " + shown(value));
  if (typeof value === "number") {
    if (schema.minimum !== undefined && !(value >= schema.minimum))
      return subject("must be at least " + schema.minimum + ", got " + value);
    if (schema.exclusiveMinimum !== undefined && !(value > schema.exclusiveMinimum))
      return subject("must be more than " + schema.exclusiveMinimum + ", got " + value);
    if (schema.maximum !== undefined && !(value <= schema.maximum))
      return subject("must be at most " + schema.maximum + ", got " + value);
    if (schema.exclusiveMaximum !== undefined && !(value < schema.exclusiveMaximum))
      return subject("must be less than " + schema.exclusiveMaximum + ", got " + value);
  }
  if (typeof value === "string") {
    const length = [...value].length;   // JSON Schema counts characters, not UTF-16 units
    if (schema.minLength !== undefined && length < schema.minLength)
      return subject("must have at least " + schema.minLength + " character(s), got " + length);
    if (schema.maxLength !== undefined && length > schema.maxLength)
      return subject("must have at most " + schema.maxLength + " character(s), got " + length);
    if (schema.pattern !== undefined && !new RegExp(schema.pattern, "u").test(value))
      return subject("must match the pattern " + schema.pattern + ", got " + shown(value));
  }
  if (type === "array") {
    if (schema.minItems !== undefined && value.length < schema.minItems)
      return subject("must have at least " + schema.minItems + " item(s), got " + value.length);
    if (schema.maxItems !== undefined && value.length > schema.maxItems)
      return subject("must have at most " + schema.maxItems + " item(s), got " + value.length);
    const prefix = schema.prefixItems || [];
    for (let i = 0; i < value.length; i++) {
      // draft 2020-12: `items` is for the elements after `prefixItems`; numbered from 1, as the
      // server's messages number them (`zone[1].polygon[2][1]`)
      const problem = schemaProblem(i < prefix.length ? prefix[i] : schema.items, value[i],
        where + "[" + (i + 1) + "]");
      if (problem) return problem;
    }
  }
  if (type === "object") {
    const key = (k) => (where ? where + "." : "") + k;
    for (const k of schema.required || [])
      if (!(k in value)) return key(k) + " is required";
    const props = schema.properties || {};
    for (const [k, v] of Object.entries(value)) {
      let problem = null;
      if (Object.hasOwn(props, k)) problem = schemaProblem(props[k], v, key(k));
      else if (schema.additionalProperties === false)
        problem = "unknown key " + key(k) + "; valid keys: " + Object.keys(props).join(", ");
      else problem = schemaProblem(schema.additionalProperties, v, key(k));
      if (problem) return problem;
    }
  }
  for (const sub of schema.allOf || []) {
    const problem = schemaProblem(sub, value, where);
    if (problem) return problem;
  }
  if (schema.anyOf && !schema.anyOf.some((sub) => !schemaProblem(sub, value, where)))
    return subject("does not match any of its forms");
  if (schema.oneOf && schema.oneOf.filter((sub) => !schemaProblem(sub, value, where)).length !== 1) {
    // the export's "exactly one of two keys" is a oneOf of one required key each
    const keys = schema.oneOf.map((sub) =>
      Object.keys(sub).length === 1 && sub.required && sub.required.length === 1 ? sub.required[0] : null);
    if (keys.every((k) => k)) return subject("needs exactly one of " + keys.join(" and "));
    return subject("must match exactly one of its forms");
  }
  return null;
}

// ---------------------------------------------------------------- editor

// Geometry is kept in the camera's source pixels: the canvas's own resolution is the scene's
// width × height, so a click maps from displayed to source pixels by the canvas's scale.
const editor = {
  camera: null,
  scene: null,           // as the server sent it (extra keys are sent back unchanged)
  lines: [],             // [{name, points: [[x, y], [x, y]]}]
  zones: [],             // [{name, polygon: [[x, y], ...], loiter_s?}]
  pending: [],           // points of the item being drawn
  dirty: false,
  schema: null,          // the scene file's JSON Schema; null: the server's check alone
  schemaLoaded: null,    // the promise of loadSchema(): a save waits for it

  async loadSchema() {
    try {
      // revalidated by its ETag, not fetched again, when the page opens once more
      this.schema = await api("api/schema/scene", { cache: "no-cache" });
    } catch (err) {
      this.schema = null;
    }
  },

  // the schema of an item of the scene's `line` or `zone` array (undefined without one)
  itemSchema(kind) {
    const table = this.schema && this.schema.properties && this.schema.properties[kind];
    return table ? table.items : undefined;
  },

  // the first problem of the lines and zones against the schema, naming the item and the key
  // ("line 2: name must match the pattern ..."), or null
  problem() {
    if (!this.schema) return null;
    for (const [kind, items] of [["line", this.lines], ["zone", this.zones]]) {
      const table = this.schema.properties && this.schema.properties[kind];
      if (!table) continue;
      for (let i = 0; i < items.length; i++) {
        const problem = schemaProblem(table.items, items[i], "");
        if (problem) return kind + " " + (i + 1) + ": " + problem;
      }
      // the array's own limits (its items are checked above, each with its number)
      const { items: _, prefixItems: __, ...own } = table;
      const problem = schemaProblem(own, items, kind + "s");
      if (problem) return problem;
    }
    return null;
  },

  // the fewest corners of a zone: the schema's, else the scene file's 3
  zoneMinPoints() {
    const polygon = this.itemSchema("zone");
    const min = polygon && polygon.properties && polygon.properties.polygon
      && polygon.properties.polygon.minItems;
    return Number.isInteger(min) ? min : 3;
  },

  init() {
    this.schemaLoaded = this.loadSchema();
    this.select = document.getElementById("editor-camera");
    this.canvas = document.getElementById("editor-canvas");
    this.picture = document.getElementById("editor-picture");
    this.select.addEventListener("change", () => this.open(this.select.value));
    this.canvas.addEventListener("click", (e) => this.click(e));
    this.canvas.addEventListener("dblclick", (e) => { e.preventDefault(); this.closeZone(); });
    this.canvas.addEventListener("keydown", (e) => {
      if (e.key === "Enter") { e.preventDefault(); this.closeZone(); }
      else if (e.key === "Escape") { this.pending = []; this.draw(); }
    });
    this.canvas.addEventListener("mousemove", (e) => { this.hover = this.toSource(e); this.draw(); });
    this.canvas.addEventListener("mouseleave", () => { this.hover = null; this.draw(); });
    document.getElementById("editor-save").addEventListener("click", () => this.save());
    document.getElementById("editor-reload").addEventListener("click", () => this.open(this.camera));
    for (const r of document.querySelectorAll('input[name="tool"]'))
      r.addEventListener("change", () => { this.pending = []; this.draw(); });
    // the editor shows a snapshot a second, not a second MJPEG stream: drawing needs the scene,
    // not motion, and every stream costs the camera's machine a decoder per open page
    setInterval(() => {
      if (this.camera && !document.hidden) this.picture.src = snapshotUrl(this.camera);
    }, 1000);
    new ResizeObserver(() => this.draw()).observe(this.canvas);
  },

  offerCameras(list) {
    const names = list.map((c) => c.name);
    const have = [...this.select.options].map((o) => o.value);
    if (names.join("\n") !== have.join("\n")) {
      this.select.replaceChildren(...list.map((c) =>
        el("option", { value: c.name, text: c.name + (c.scene ? "" : " (no scene file)") })));
      if (this.camera && names.includes(this.camera)) this.select.value = this.camera;
    }
    if (!this.camera && names.length) this.open(names[0]);
  },

  async open(name) {
    this.camera = name;
    this.select.value = name;
    this.pending = [];
    this.message("");
    this.error("");
    this.picture.src = snapshotUrl(name);
    try {
      const scene = await api(cameraPath(name, "scene"));
      this.scene = scene;
      // items given in metres (`world`) have no pixels to draw: they are listed, kept and sent
      // back as they are (the server checks them with the camera's calibration)
      this.lines = (scene.lines || []).map((l) => structuredClone(l));
      this.zones = (scene.zones || []).map((z) => structuredClone(z));
    } catch (err) {
      this.scene = null;
      this.lines = [];
      this.zones = [];
      this.error(err.message);
    }
    this.dirty = false;
    this.sizeCanvas();
    this.renderItems();
    this.draw();
  },

  // source size: the scene's, else the picture's own
  size() {
    const w = (this.scene && this.scene.width) || this.picture.naturalWidth || 640;
    const h = (this.scene && this.scene.height) || this.picture.naturalHeight || 480;
    return [w, h];
  },

  sizeCanvas() {
    const [w, h] = this.size();
    if (this.canvas.width !== w) this.canvas.width = w;
    if (this.canvas.height !== h) this.canvas.height = h;
    this.canvas.closest(".stage").style.aspectRatio = w + " / " + h;
  },

  toSource(e) {
    const rect = this.canvas.getBoundingClientRect();
    const x = (e.clientX - rect.left) * (this.canvas.width / rect.width);
    const y = (e.clientY - rect.top) * (this.canvas.height / rect.height);
    return [Math.round(x * 4) / 4, Math.round(y * 4) / 4];
  },

  tool() {
    return document.querySelector('input[name="tool"]:checked').value;
  },

  nextName(kind) {
    const field = document.getElementById("editor-name");
    const typed = field.value.trim();
    field.value = "";
    if (typed) return typed;
    const taken = new Set((kind === "line" ? this.lines : this.zones).map((i) => i.name));
    for (let i = 1; ; i++) if (!taken.has(kind + i)) return kind + i;
  },

  click(e) {
    if (!this.camera) return;
    this.canvas.focus();
    const p = this.toSource(e);
    const last = this.pending[this.pending.length - 1];
    // the clicks of a double-click land on the same spot: one point
    if (last && Math.hypot(last[0] - p[0], last[1] - p[1]) < 1) return;
    this.pending.push(p);
    if (this.tool() === "line" && this.pending.length === 2) {
      this.lines.push({ name: this.nextName("line"), points: this.pending });
      this.pending = [];
      this.changed();
    }
    this.draw();
  },

  closeZone() {
    if (this.tool() !== "zone") return;
    const min = this.zoneMinPoints();
    if (this.pending.length < min) {
      this.message("a zone needs at least " + min + " points");
      return;
    }
    this.zones.push({ name: this.nextName("zone"), polygon: this.pending });
    this.pending = [];
    this.changed();
    this.draw();
  },

  changed() {
    this.dirty = true;
    this.message("unsaved changes");
    this.renderItems();
  },

  renderItems() {
    const render = (listId, items, kind) => {
      const ul = document.getElementById(listId);
      ul.replaceChildren(...items.map((item, i) => {
        const input = el("input", {
          type: "text", value: item.name, "aria-label": "Name of " + kind + " " + (i + 1),
          title: item.world ? "in metres: not drawn on the picture" : "",
          "data-testid": "editor-" + kind + "-name-" + i,
          oninput: (e) => { item.name = e.target.value; this.dirty = true; this.message("unsaved changes"); this.draw(); },
        });
        const del = el("button", {
          type: "button", text: "Delete", "aria-label": "Delete " + kind + " " + item.name,
          "data-testid": "editor-" + kind + "-delete-" + i,
          onclick: () => { items.splice(i, 1); this.changed(); this.draw(); },
        });
        return el("li", { "data-testid": "editor-" + kind + "-" + i }, input, del);
      }));
    };
    render("editor-lines", this.lines, "line");
    render("editor-zones", this.zones, "zone");
  },

  draw() {
    const ctx = this.canvas.getContext("2d");
    this.sizeCanvas();
    const [w] = this.size();
    const u = Math.max(1, w / 640);          // line widths and text scale with the source size
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.lineWidth = 2 * u;
    ctx.font = `${Math.round(14 * u)}px sans-serif`;
    const path = (pts, close) => {
      ctx.beginPath();
      pts.forEach((p, i) => (i ? ctx.lineTo(p[0], p[1]) : ctx.moveTo(p[0], p[1])));
      if (close) ctx.closePath();
    };
    for (const z of this.zones) {
      if (!z.polygon) continue;
      ctx.strokeStyle = "#ffb000"; ctx.fillStyle = "rgba(255, 176, 0, 0.15)";
      path(z.polygon, true); ctx.fill(); ctx.stroke();
      ctx.fillStyle = "#ffb000"; ctx.fillText(z.name, z.polygon[0][0] + 4 * u, z.polygon[0][1] + 16 * u);
    }
    for (const l of this.lines) {
      if (!l.points) continue;
      ctx.strokeStyle = "#00e0ff"; path(l.points, false); ctx.stroke();
      ctx.fillStyle = "#00e0ff"; ctx.fillText(l.name, l.points[0][0] + 4 * u, l.points[0][1] - 4 * u);
    }
    if (this.pending.length) {
      ctx.strokeStyle = "#ff3b3b";
      path(this.hover ? [...this.pending, this.hover] : this.pending, false); ctx.stroke();
      ctx.fillStyle = "#ff3b3b";
      for (const p of this.pending) ctx.fillRect(p[0] - 3 * u, p[1] - 3 * u, 6 * u, 6 * u);
    }
  },

  async save() {
    if (!this.camera) return;
    this.error("");
    await this.schemaLoaded;
    const problem = this.problem();
    if (problem) {
      this.message("");
      this.error("not saved: " + problem);
      return;
    }
    const body = { ...(this.scene || {}), lines: this.lines, zones: this.zones };
    try {
      await api(cameraPath(this.camera, "scene"), {
        method: "PUT",
        headers: { "Content-Type": "application/json" },
        body: JSON.stringify(body),
      });
      this.dirty = false;
      this.message("saved: " + this.lines.length + " line(s), " + this.zones.length + " zone(s)");
      this.canvas.dataset.saved = String(Date.now());
      const name = this.camera;
      setTimeout(() => refreshCounts(name), 500);
    } catch (err) {
      this.message("");
      this.error((err.status ? "not saved (" + err.status + "): " : "not saved: ") + err.message);
    }
  },

  message(text) {
    document.getElementById("editor-message").textContent = text;
  },

  error(text) {
    const box = document.getElementById("editor-error");
    box.textContent = text;
    box.hidden = !text;
  },
};

// ---------------------------------------------------------------- start

function start() {
  editor.init();
  pollCameras();
  setInterval(pollCameras, POLL_MS);
  setInterval(() => { for (const name of counts.keys()) refreshCounts(name); }, COUNTS_POLL_MS);
  listen();
}

if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
else start();

// The live page of a running controller: one more client of its services interface (docs/live.md).
// It reads the routes every client reads (/, /components, /openapi.json, /requests, /tasks, the event stream)
// and sends requests as the Python client does, with the token as "Authorization: Bearer" when there is one.
// Events are queued as they arrive and applied together at most every FLUSH_MS.
"use strict";

const FLUSH_MS = 66;            // apply queued events at most 15 times a second (the page must keep 10)
const TASKS_MS = 1000;          // how often the task table and plot are read
const HISTORY = 240;            // samples kept per plotted value
const MAX_PLOTS = 6;            // numeric fields plotted per poster
const MAX_LOG = 300;            // requests kept in the log
const MAX_PAST = 100;           // requests read at start, with their reports
const MAX_ALERTS = 100;
const STATES = ["idle", "queued", "validating", "running", "ok", "rejected", "failed", "interrupted"];
const TOKEN_KEY = "genom2bip-token";

const PLOT_MS = 200;            // a poster's plots are redrawn at most 5 times a second (its value at every update)
const $ = (id) => document.getElementById(id);

function setText(el, text) {  // a text set to what it already says would still make the browser lay out and paint
  if (el.textContent !== text) el.textContent = text;
}
const live = window.live = {
  token: sessionStorage.getItem(TOKEN_KEY), system: null, components: {}, openapi: null, types: {},
  services: {}, requests: new Map(), posters: {}, poses: [], scene: null, mine: new Set(),
  queue: [], stats: {events: 0, updates: 0, rate: 0, window: []}, tasks: {}, taskHistory: [],
  stopped: false, streamOpen: false, seen: new Set(), dirty: new Set(), overruns: new Map(),
};

// What is off the screen is not drawn (it costs the browser's CPU, on the controller's machine perhaps): it is
// marked dirty and drawn when it scrolls into view.
const watcher = new IntersectionObserver((entries) => {
  for (const entry of entries) {
    if (entry.isIntersecting) live.seen.add(entry.target); else live.seen.delete(entry.target);
  }
});

function visible(el) {
  if (live.seen.has(el)) { live.dirty.delete(el); return true; }
  live.dirty.add(el);
  return false;
}

function redraw(el) {
  live.dirty.delete(el);
  if (el.id === "world") drawWorld();
  else if (el.id === "tasks-plot") plotTasks();
  else if (el.id.startsWith("poster-")) drawPoster(el.id.slice("poster-".length));
}

// ---- talking to the server --------------------------------------------------------------------------------

class Refused extends Error {}

async function api(path, options = {}) {
  const headers = Object.assign({Accept: "application/json"}, options.headers || {});
  if (live.token) headers.Authorization = "Bearer " + live.token;
  const response = await fetch(path, Object.assign({}, options, {headers}));
  if (response.status === 401) {
    const body = await response.json().catch(() => ({}));
    throw new Refused(body.error || "the token was refused");
  }
  return response;
}

async function json(path) {
  const response = await api(path);
  const body = await response.json();
  if (!response.ok) throw new Error(`${path}: ${body.error || response.status}`);
  return body;
}

function askToken(why) {
  $("main").hidden = true;
  $("login").hidden = false;
  $("login-why").textContent = why;
  setBadge("status", "refused", "token needed");
  $("token").focus();
}

$("login-form").addEventListener("submit", (event) => {
  event.preventDefault();
  live.token = $("token").value;
  sessionStorage.setItem(TOKEN_KEY, live.token);
  if (live.booted) location.reload();  // refused after it had started (the server's token changed): start afresh
  else boot();
});

function problem(text) {
  $("problem").hidden = !text;
  $("problem").textContent = text || "";
}

function setBadge(id, status, text) {
  $(id).dataset.status = status;
  $(id).textContent = text;
}

// ---- start ------------------------------------------------------------------------------------------------

async function boot() {
  let summary;
  try {
    summary = await json("/");
  } catch (err) {
    if (err instanceof Refused) {
      const had = live.token;
      live.token = null;
      sessionStorage.removeItem(TOKEN_KEY);
      askToken(had ? `Refused: ${err.message}` : "Give the token the controller was started with.");
      return;
    }
    problem(`cannot reach the controller: ${err.message}`);
    return;
  }
  $("login").hidden = true;
  $("main").hidden = false;
  live.system = summary.system;
  $("system").textContent = summary.system || "controller";
  document.title = `${summary.system} live`;
  setBadge("status", summary.status, summary.status);
  live.booted = true;  // from here a token asked again reloads the page rather than building it twice
  try {
    await load();
  } catch (err) {
    if (err instanceof Refused) { askToken(`Refused: ${err.message}`); return; }
    problem(err.message);
    return;
  }
  stream();
  setInterval(flush, FLUSH_MS);
  setInterval(readTasks, TASKS_MS);
  readTasks();
}

async function load() {
  const [components, openapi, recent] = await Promise.all([json("/components"), json("/openapi.json"),
                                                          json("/requests?limit=" + MAX_PAST)]);
  live.openapi = openapi;
  for (const c of components) {
    const detail = await json(`/components/${encodeURIComponent(c.name)}`);
    live.components[c.name] = detail;
    Object.assign(live.types, detail.types || {});
    for (const s of detail.services) live.services[`${c.name}.${s.name}`] = {state: "idle", request: null};
  }
  buildForms();
  for (const row of recent.reverse()) {
    const req = await json(`/requests/${row.id}`);
    for (const r of req.reports) applyReport(r);
    const svc = live.services[`${row.component}.${row.service}`];
    if (svc) svc.state = {queued: "queued", running: "running"}[req.status] || req.status;
  }
  await buildPosters();
  await drawLevel();
  try {
    const response = await api("/scene");
    if (response.ok) live.scene = await response.json();
  } catch (err) {
    if (err instanceof Refused) throw err;
  }
  if (live.scene) {
    $("mission-panel").hidden = false;
    $("mission-name").textContent = live.scene.name || "";
    const pose = live.scene.pose;  // the pose the robot navigates by, in the world's frame
    if (pose) live.poses = live.poses.filter((p) => p.poster === pose.poster && p.path === pose.path);
    const [x0, y0, x1, y1] = live.scene.bounds;
    const canvas = $("world");
    canvas.height = Math.round(Math.min(480, Math.max(120, (canvas.width - 20) * (y1 - y0) / (x1 - x0) + 20)));
  }
  paintStates();
}

// ---- the event stream (server-sent events read through fetch, so that the token goes in a header) ---------

async function stream() {
  let response;
  try {
    response = await api("/events", {headers: {Accept: "text/event-stream"}});
  } catch (err) {
    if (err instanceof Refused) { askToken(`Refused: ${err.message}`); return; }
    setBadge("stream", "closed", "stream lost");
    setTimeout(stream, 2000);
    return;
  }
  if (!response.ok) { setBadge("stream", "closed", `stream refused (${response.status})`); return; }
  setBadge("stream", "open", "stream open");
  live.streamOpen = true;
  const reader = response.body.getReader();
  const decoder = new TextDecoder();
  let buffer = "";
  for (;;) {
    let chunk;
    try {
      chunk = await reader.read();
    } catch (err) {
      break;
    }
    if (chunk.done) break;
    buffer += decoder.decode(chunk.value, {stream: true});
    let end;
    while ((end = buffer.indexOf("\n\n")) >= 0) {
      const frame = buffer.slice(0, end);
      buffer = buffer.slice(end + 2);
      const event = parseFrame(frame);
      if (event) live.queue.push(event);
    }
  }
  live.streamOpen = false;
  setBadge("stream", "closed", "stream ended");
  if (!live.stopped) setTimeout(stream, 2000);
}

function parseFrame(frame) {
  let kind = "message";
  const data = [];
  for (const line of frame.split("\n")) {
    if (line.startsWith(":")) continue;
    if (line.startsWith("event:")) kind = line.slice(6).trim();
    else if (line.startsWith("data:")) data.push(line.slice(5).replace(/^ /, ""));
  }
  if (!data.length) return null;
  try {
    const body = JSON.parse(data.join("\n"));
    return Object.assign({event: kind}, body, {event: kind});
  } catch (err) {
    return null;
  }
}

// ---- applying events ----------------------------------------------------------------------------------------

function flush() {
  const now = performance.now();
  const w = live.stats.window;
  while (w.length && now - w[0] > 1000) w.shift();
  if (live.queue.length) {
    const events = live.queue;
    live.queue = [];
    const changed = new Set();
    let states = false;
    for (const e of events) {
      apply(e, changed);
      states = states || e.event === "service" || e.event === "report";
    }
    live.stats.events += events.length;
    live.stats.updates += 1;
    w.push(now);
    for (const key of changed) drawPoster(key);
    if (changed.size && live.scene) drawWorld();
    if (states) paintStates();
  }
  for (const el of [...live.dirty]) if (live.seen.has(el)) redraw(el);
  live.stats.rate = w.length;
  setText($("rate"), `${w.length} updates/s`);
}

function apply(e, changed) {
  switch (e.event) {
    case "hello":
      setBadge("status", e.status, e.status);
      break;
    case "controller":
      if (e.status) setBadge("status", e.status, e.status);
      if (e.status === "stopped" || e.status === "error") live.stopped = true;
      break;
    case "report":
      applyReport(e);
      break;
    case "service": {
      const svc = live.services[e.service];
      if (svc) {
        svc.state = e.state === "idle" ? (e.outcome || "idle") : e.state;
        svc.request = e.request;
      }
      break;
    }
    case "poster":
      posterValue(e.component, e.port, e.value, e.seq);
      changed.add(`${e.component}.${e.port}`);
      break;
    case "observer": case "overrun": case "codel_overrun": case "codel_error":
      alert(e);
      break;
    case "gap": case "overflow":
      alert(Object.assign({}, e, {message: e.message}));
      break;
  }
}

function applyReport(r) {
  const label = `${r.component}.${r.service}`;
  let entry = live.requests.get(r.request);
  if (!entry) {
    entry = {id: r.request, label, reports: [], li: null};
    live.requests.set(r.request, entry);
    const svc = live.services[label];
    if (svc && r.status === "queued" && !["validating", "running"].includes(svc.state)) svc.state = "queued";
  }
  if (entry.reports.some((x) => x.status === r.status && x.step === r.step)) return;
  entry.reports.push(r);
  if (r.final) {
    const svc = live.services[label];
    if (svc && (svc.request === null || svc.request <= r.request)) { svc.state = r.status; svc.request = r.request; }
  }
  drawRequest(entry);
}

// ---- the functional level and the module view ---------------------------------------------------------------

async function svg(path) {
  const response = await api(path);
  if (!response.ok) {
    const body = await response.json().catch(() => ({}));
    throw new Error(`${path}: ${body.error || response.status}`);
  }
  const doc = new DOMParser().parseFromString(await response.text(), "image/svg+xml");
  const root = doc.documentElement;
  if (root.nodeName !== "svg") throw new Error(`${path}: not a picture`);
  for (const bad of root.querySelectorAll("script, foreignObject")) bad.remove();
  return document.importNode(root, true);
}

function title(g) {
  const t = g.querySelector(":scope > title");
  return t ? t.textContent : "";
}

async function drawLevel() {
  let picture;
  try {
    picture = await svg("/pictures/level.svg");
  } catch (err) {
    if (err instanceof Refused) throw err;
    $("level").textContent = `no picture: ${err.message}`;
    return;
  }
  $("level").replaceChildren(picture);
  for (const g of picture.querySelectorAll("g.node")) {
    const module = title(g);
    const comp = live.components[module];
    if (!comp) continue;
    g.classList.add("module");
    g.addEventListener("click", () => openModule(module));
    const names = new Map(comp.services.map((s) => [s.name, `${module}.${s.name}`]));
    for (const text of g.querySelectorAll("text")) {
      const label = names.get(text.textContent.trim());
      if (!label) continue;
      // The service's row of its module's table (its cell's frame is drawn just before its text), else its text.
      const cell = text.previousElementSibling;
      const framed = cell && cell.tagName === "polygon";
      const box = framed ? cell.getBBox() : text.getBBox();
      const pad = framed ? -1 : 3;
      const rect = document.createElementNS("http://www.w3.org/2000/svg", "rect");
      rect.setAttribute("class", "svc-bg");
      rect.setAttribute("x", box.x - pad); rect.setAttribute("y", box.y - pad / 3);
      rect.setAttribute("width", box.width + 2 * pad); rect.setAttribute("height", box.height + 2 * pad / 3);
      rect.setAttribute("rx", framed ? 0 : 3);
      rect.dataset.service = label;
      text.before(rect);
      text.dataset.service = label;
    }
  }
}

async function openModule(module) {
  $("module-view").hidden = false;
  $("module-name").textContent = module;
  $("module").textContent = "laying out…";
  try {
    const picture = await svg(`/pictures/modules/${encodeURIComponent(module)}.svg`);
    $("module").replaceChildren(picture);
    for (const g of picture.querySelectorAll("g.node")) {
      const atom = title(g);
      const m = atom.match(/^(.*)\.(control|activity)$/);
      if (m && live.services[m[1]]) g.dataset.service = m[1];
    }
    paintStates();
    $("module-view").scrollIntoView({block: "nearest"});
  } catch (err) {
    if (err instanceof Refused) { askToken(`Refused: ${err.message}`); return; }
    $("module").textContent = err.message;
  }
}

$("module-close").addEventListener("click", () => { $("module-view").hidden = true; });

function paintStates() {
  for (const el of document.querySelectorAll("[data-service]")) {
    const svc = live.services[el.dataset.service];
    if (!svc) continue;
    if (el.dataset.state !== svc.state) el.dataset.state = svc.state;
    if (el.tagName === "rect" || el.tagName === "g") {
      let tip = el.querySelector(":scope > title.state-tip");
      if (!tip) {
        tip = document.createElementNS("http://www.w3.org/2000/svg", "title");
        tip.setAttribute("class", "state-tip");
        el.prepend(tip);
      }
      tip.textContent = `${el.dataset.service}: ${svc.state}` + (svc.request ? ` (request ${svc.request})` : "");
    }
  }
  const current = $("service-select").value;
  if (current && live.services[current]) {
    const badge = $("service-state");
    const state = live.services[current].state;
    badge.innerHTML = "";
    const span = document.createElement("span");
    span.className = "state";
    span.dataset.state = state;
    span.textContent = `${current}: ${state}`;
    badge.append(span);
  }
}

// ---- requests -------------------------------------------------------------------------------------------------

function describe(r) {
  if (r.status === "rejected" && r.reason === "rule") return `by rule ${r.rule}`;
  if (r.status === "rejected") return `by its validate codel${r.codel ? " " + r.codel : ""}: ${r.exception || r.message}`;
  if (r.status === "failed") {
    const what = r.exception || r.error || "";
    return `${what}${r.codel ? " in " + r.codel : ""}${r.message && r.message !== what ? " — " + r.message : ""}`;
  }
  if (r.status === "interrupted") return r.by ? `by ${r.by} (request ${r.by_request})` : (r.message || "");
  if (r.status === "held") return `held by ${(r.rules || []).join(", ")}`;
  if (r.status === "ok" && r.outputs && Object.keys(r.outputs).length) return JSON.stringify(r.outputs);
  return "";
}

function drawRequest(entry) {
  let li = entry.li;
  if (!li) {
    li = entry.li = document.createElement("li");
    li.id = `request-${entry.id}`;
    li.innerHTML = '<div class="head"><span class="id"></span><b class="label"></b><span class="state"></span>' +
      '<span class="why"></span></div><div class="reports"></div>';
    li.querySelector(".id").textContent = `#${entry.id}`;
    li.querySelector(".label").textContent = entry.label;
    const list = $("requests");
    const after = [...list.children].find((x) => Number(x.id.split("-")[1]) < entry.id);
    list.insertBefore(li, after || null);
    while (list.children.length > MAX_LOG) {
      const last = list.lastElementChild;
      live.requests.delete(Number(last.id.split("-")[1]));
      last.remove();
    }
  }
  const reports = [...entry.reports].sort((a, b) => a.step - b.step || a.time - b.time);
  const last = reports.find((r) => r.final) || reports[reports.length - 1];
  li.dataset.status = last.status;
  if (live.mine.has(entry.id)) li.classList.add("mine");
  const state = li.querySelector(".state");
  state.dataset.state = last.status === "started" ? "running" : last.status;
  state.textContent = last.status;
  li.querySelector(".why").textContent = describe(last);
  li.querySelector(".reports").textContent = reports.map(
    (r) => `${r.status}${r.final ? " (final)" : ""} at ${Number(r.time).toFixed(3)} s, step ${r.step}` +
           (r.final || !describe(r) ? "" : `: ${describe(r)}`)).join(" → ");
}

// ---- forms from the OpenAPI document ---------------------------------------------------------------------------

function resolve(schema) {
  let s = schema || {};
  for (let i = 0; s.$ref && i < 20; i++) {  // "#/components/schemas/dala.pose" (OpenAPI) or "dala::pose" (interface)
    s = (s.$ref.startsWith("#/") ? s.$ref.split("/").slice(1).reduce((node, key) => (node || {})[key], live.openapi)
      : live.types[s.$ref]) || {};
  }
  return s;
}

function buildForms() {
  const select = $("service-select");
  for (const [path, item] of Object.entries(live.openapi.paths)) {
    const m = path.match(/^\/components\/([^/]+)\/services\/([^/]+)$/);
    if (!m || !item.post) continue;
    const option = document.createElement("option");
    option.value = `${m[1]}.${m[2]}`;
    option.textContent = `${m[1]}.${m[2]}`;
    select.append(option);
  }
  select.addEventListener("change", showForm);
  showForm();
}

function showForm() {
  const label = $("service-select").value;
  const [c, s] = label.split(".");
  const item = live.openapi.paths[`/components/${c}/services/${s}`].post;
  const schema = resolve(item.requestBody.content["application/json"].schema);
  const form = $("service-form");
  form.replaceChildren();
  form.dataset.service = label;
  if (item.description) {
    const doc = document.createElement("p");
    doc.className = "hint";
    doc.textContent = item.description;
    form.append(doc);
  }
  for (const [name, prop] of Object.entries(schema.properties || {})) {
    form.append(field(name, name, prop, prop.default));
  }
  const button = document.createElement("button");
  button.type = "submit";
  button.textContent = `Send ${label}`;
  form.append(button);
  $("send-result").textContent = "";
  paintStates();
}

function field(path, name, schema, value) {
  const s = resolve(schema);
  if (s.type === "object" && s.properties) {
    const set = document.createElement("fieldset");
    const legend = document.createElement("legend");
    legend.textContent = name + (schema.description ? ` — ${schema.description}` : "");
    set.append(legend);
    for (const [key, sub] of Object.entries(s.properties)) {
      set.append(field(`${path}.${key}`, key, sub, value && typeof value === "object" ? value[key] : undefined));
    }
    return set;
  }
  const label = document.createElement("label");
  const caption = document.createElement("span");
  caption.textContent = name;
  label.append(caption);
  let input;
  if (s.enum) {
    input = document.createElement("select");
    for (const v of s.enum) {
      const o = document.createElement("option");
      o.value = o.textContent = v;
      input.append(o);
    }
    if (value !== undefined) input.value = value;
    input.dataset.kind = "string";
  } else if (s.type === "number" || s.type === "integer") {
    input = document.createElement("input");
    input.type = "number";
    input.step = s.type === "integer" ? "1" : "any";
    if (value !== undefined && value !== null) input.value = value;
    input.dataset.kind = s.type;
  } else if (s.type === "boolean") {
    input = document.createElement("input");
    input.type = "checkbox";
    input.checked = Boolean(value);
    input.dataset.kind = "boolean";
  } else if (s.type === "string") {
    input = document.createElement("input");
    input.type = "text";
    if (value !== undefined) input.value = value;
    input.dataset.kind = "string";
  } else {
    input = document.createElement("textarea");
    input.value = value === undefined ? "" : JSON.stringify(value);
    input.dataset.kind = "json";
    input.placeholder = "JSON";
  }
  input.name = path;
  if (schema.description) label.title = schema.description;
  label.append(input);
  return label;
}

function formInputs(form) {
  const out = {};
  for (const input of form.querySelectorAll("[name]")) {
    let value;
    const kind = input.dataset.kind;
    if (kind === "boolean") value = input.checked;
    else if (input.value === "") continue;  // left empty: the service's default
    else if (kind === "number" || kind === "integer") value = Number(input.value);
    else if (kind === "json") value = JSON.parse(input.value);
    else value = input.value;
    const keys = input.name.split(".");
    let node = out;
    for (const k of keys.slice(0, -1)) node = node[k] = node[k] || {};
    node[keys[keys.length - 1]] = value;
  }
  return out;
}

$("service-form").addEventListener("submit", async (event) => {
  event.preventDefault();
  const form = event.target;
  const [c, s] = form.dataset.service.split(".");
  const result = $("send-result");
  let body;
  try {
    body = JSON.stringify(formInputs(form));
  } catch (err) {
    result.textContent = `not sent: ${err.message}`;
    return;
  }
  try {
    const response = await api(`/components/${c}/services/${s}`, {
      method: "POST", body, headers: {"Content-Type": "application/json"}});
    const answer = await response.json();
    if (!response.ok) {
      result.textContent = `refused (${response.status}): ${answer.error}`;
      result.dataset.status = "error";
      return;
    }
    live.mine.add(answer.id);
    result.dataset.status = "queued";
    result.dataset.request = answer.id;
    result.textContent = `request #${answer.id} queued: it follows in the log`;
    const entry = live.requests.get(answer.id);
    if (entry) drawRequest(entry);
  } catch (err) {
    if (err instanceof Refused) { askToken(`Refused: ${err.message}`); return; }
    result.textContent = `not sent: ${err.message}`;
  }
});

// ---- posters -----------------------------------------------------------------------------------------------------

function numericPaths(value, prefix, out) {
  if (typeof value === "number") out.push(prefix);
  else if (value && typeof value === "object" && !Array.isArray(value)) {
    for (const [k, v] of Object.entries(value)) numericPaths(v, prefix ? `${prefix}.${k}` : k, out);
  }
  return out;
}

function at(value, path) {
  return path ? path.split(".").reduce((node, k) => (node == null ? undefined : node[k]), value) : value;
}

function poseIn(schema, prefix, out) {
  const s = resolve(schema);
  if (s.type !== "object" || !s.properties) return out;
  const keys = Object.keys(s.properties);
  if (["x", "y", "theta"].every((k) => keys.includes(k))) out.push(prefix);
  else for (const [k, sub] of Object.entries(s.properties)) poseIn(sub, prefix ? `${prefix}.${k}` : k, out);
  return out;
}

async function buildPosters() {
  const box = $("posters");
  for (const [c, comp] of Object.entries(live.components)) {
    for (const port of comp.ports || []) {
      if (port.direction !== "out") continue;
      const key = `${c}.${port.name}`;
      const card = document.createElement("div");
      card.className = "poster";
      card.id = `poster-${key}`;
      card.innerHTML = '<h3></h3><pre></pre><div class="plots"></div>';
      card.querySelector("h3").textContent = key;
      box.append(card);
      live.posters[key] = {card, value: undefined, seq: 0, history: {}, paths: null};
      watcher.observe(card);
      for (const path of poseIn(port.schema, "", [])) live.poses.push({poster: key, path, trail: []});  // kept if
      // the scene names none
      const answer = await json(`/components/${c}/ports/${port.name}`);
      if (answer.written) posterValue(c, port.name, answer.value, answer.seq);
      if (answer.failure) card.classList.add("stale");
      drawPoster(key);
    }
  }
}

function posterValue(c, p, value, seq) {
  const poster = live.posters[`${c}.${p}`];
  if (!poster) return;
  poster.value = value;
  poster.seq = seq;
  poster.card.classList.remove("stale");
  if (!poster.paths) poster.paths = numericPaths(value, "", []).slice(0, MAX_PLOTS);
  const t = performance.now() / 1000;
  for (const path of poster.paths) {
    const h = poster.history[path] = poster.history[path] || [];
    h.push([t, at(value, path)]);
    if (h.length > HISTORY) h.shift();
  }
  for (const pose of live.poses) {
    if (pose.poster !== `${c}.${p}`) continue;
    const q = at(value, pose.path);
    if (q && typeof q.x === "number") {
      pose.now = q;
      const lastPoint = pose.trail[pose.trail.length - 1];
      if (!lastPoint || Math.hypot(lastPoint[0] - q.x, lastPoint[1] - q.y) > 0.01) pose.trail.push([q.x, q.y]);
      if (pose.trail.length > 20000) pose.trail.shift();
    }
  }
}

function shortJson(value) {
  return JSON.stringify(value, (k, v) => (Array.isArray(v) && v.length > 8
    ? `[${v.length} items: ${v.slice(0, 4).map((x) => (typeof x === "number" ? x.toFixed(3) : JSON.stringify(x))).join(", ")} …]`
    : typeof v === "number" && !Number.isInteger(v) ? Number(v.toFixed(4)) : v)).replace(/,"/g, ', "');
}

function drawPoster(key) {
  const poster = live.posters[key];
  if (!poster || !visible(poster.card)) return;
  setText(poster.card.querySelector("pre"),
          poster.value === undefined ? "(not written yet)" : `#${poster.seq} ${shortJson(poster.value)}`);
  const now = performance.now();
  if (now - (poster.plotted || 0) < PLOT_MS) {
    live.dirty.add(poster.card);  // drawn at a later update
    return;
  }
  poster.plotted = now;
  const plots = poster.card.querySelector(".plots");
  for (const path of poster.paths || []) {
    let canvas = plots.querySelector(`canvas[data-path="${CSS.escape(path)}"]`);
    if (!canvas) {
      const fig = document.createElement("figure");
      canvas = document.createElement("canvas");
      canvas.width = 120;
      canvas.height = 36;
      canvas.dataset.path = path;
      const cap = document.createElement("figcaption");
      fig.append(canvas, cap);
      plots.append(fig);
    }
    const h = poster.history[path] || [];
    const last = h.length ? h[h.length - 1][1] : undefined;
    setText(canvas.nextSibling, `${path} ${typeof last === "number" ? last.toFixed(3) : ""}`);
    sparkline(canvas, h);
  }
}

function sparkline(canvas, points) {
  const ctx = canvas.getContext("2d");
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  if (points.length < 2) return;
  let lo = Infinity, hi = -Infinity;
  for (const [, v] of points) { if (v < lo) lo = v; if (v > hi) hi = v; }
  if (hi - lo < 1e-9) { hi += 0.5; lo -= 0.5; }
  const t0 = points[0][0], t1 = points[points.length - 1][0] || t0 + 1;
  ctx.strokeStyle = "#2a62b8";
  ctx.lineWidth = 1.2;
  ctx.beginPath();
  points.forEach(([t, v], i) => {
    const x = ((t - t0) / Math.max(t1 - t0, 1e-6)) * (canvas.width - 2) + 1;
    const y = canvas.height - 2 - ((v - lo) / (hi - lo)) * (canvas.height - 4);
    if (i) ctx.lineTo(x, y); else ctx.moveTo(x, y);
  });
  ctx.stroke();
}

// ---- monitoring --------------------------------------------------------------------------------------------------

function alert(e) {
  if (e.event === "overrun" || e.event === "codel_overrun") {
    overrun(e);
    return;
  }
  const list = $("alerts");
  const li = document.createElement("li");
  li.className = e.event;
  li.dataset.kind = e.event;
  if (e.observer) li.dataset.observer = e.observer;
  const head = document.createElement("div");
  head.innerHTML = "<b></b> <span></span>";
  head.querySelector("b").textContent = e.event === "observer" ? "observer violated" : e.event.replace("_", " ");
  head.querySelector("span").textContent = e.message || JSON.stringify(e);
  li.append(head);
  if (Array.isArray(e.events) && e.events.length) {
    const trail = document.createElement("div");
    trail.className = "trail";
    trail.textContent = "led to it: ";
    for (const step of e.events) {
      const span = document.createElement("span");
      span.textContent = `${step.label} @ ${Number(step.at_ms).toFixed(1)} ms`;
      trail.append(span);
    }
    li.append(trail);
  }
  if (e.action) {
    const act = document.createElement("div");
    act.className = "trail";
    act.textContent = `action: ${e.action.service} ` + (e.action.request ? `(request ${e.action.request})` : e.action.refused || "");
    li.append(act);
  }
  list.prepend(li);
  while (list.children.length > MAX_ALERTS) list.lastElementChild.remove();
  $("alert-count").textContent = `${list.children.length} shown`;
}

function overrun(e) {
  // One line per task (or codel) that overran, with its count and the last message: they can come every period.
  // A task's count is the controller's own (the event carries it, GET /tasks too) and the task table shows the same
  // number, the larger of the two: the page opened late, or a stream that fell behind, does not make it smaller, and
  // the table does not wait for its next reading.  A codel's count is what the page saw, and says so.
  const key = `${e.event}:${e.task || e.codel || ""}`;
  const li = overrunLine(key, e.event);
  if (e.event === "overrun" && typeof e.overruns === "number") li.count = Math.max(li.count, e.overruns);
  else li.count += 1;
  li.last = `last: ${e.message || JSON.stringify(e)}`;
  showOverrun(li);
}

function overrunLine(key, kind) {
  let li = live.overruns.get(key);
  if (!li) {
    li = document.createElement("li");
    li.className = kind;
    li.dataset.kind = kind;
    li.dataset.key = key;
    li.innerHTML = '<b></b> <span class="count"></span> <span class="last"></span>';
    live.overruns.set(key, li);
    li.count = 0;
    li.last = "";
  }
  return li;
}

function showOverrun(li) {
  li.dataset.count = li.count;
  const task = li.dataset.kind === "overrun" ? li.dataset.key.slice("overrun:".length) : null;
  setText(li.querySelector("b"), task ? `${task} overran` : "codel overrun");
  const times = li.count === 1 ? "once" : `${li.count} times`;
  setText(li.querySelector(".count"), task ? `${times};` : `${li.count} since the page opened;`);
  setText(li.querySelector(".last"), li.last);
  if ($("overruns").firstElementChild !== li) $("overruns").prepend(li);
  if (task) {
    const row = $("tasks").querySelector(`tbody tr[data-task="${CSS.escape(task)}"]`);
    if (row) setText(row.cells[OVERRUNS], String(li.count));
  }
}

function tasksOverran(tasks) {
  // The table and the lines say the same count: a task that overran before the page opened gets its line too.
  for (const task of tasks) {
    if (!task.overruns && !live.overruns.has(`overrun:${task.task}`)) continue;
    const li = overrunLine(`overrun:${task.task}`, "overrun");
    li.count = Math.max(li.count, task.overruns);
    if (!li.last) li.last = "(before the page opened)";
    showOverrun(li);
  }
}

async function readTasks() {
  let tasks;
  try {
    tasks = await json("/tasks");
  } catch (err) {
    if (err instanceof Refused) askToken(`Refused: ${err.message}`);
    return;
  }
  const t = performance.now() / 1000;
  live.taskHistory.push([t, tasks]);
  if (live.taskHistory.length > HISTORY) live.taskHistory.shift();
  const body = $("tasks").querySelector("tbody");
  body.replaceChildren();
  for (const task of tasks) {
    const tr = document.createElement("tr");
    tr.dataset.task = task.task;
    if (task.missed) tr.className = "missed";
    const lat = task.lateness_ms || {};
    const f = (v) => (v == null ? "–" : Number(v).toFixed(2));
    for (const cell of [task.task, `${task.period_ms} ms`, task.periods, task.missed, task.overruns,
                        `${f(lat.p50)} / ${f(lat.p99)} / ${f(lat.max)}`]) {
      const td = document.createElement("td");
      td.textContent = cell;
      tr.append(td);
    }
    body.append(tr);
  }
  tasksOverran(tasks);
  plotTasks();
  try {
    const summary = await json("/");
    setText($("uptime"), `up ${summary.uptime.toFixed(1)} s, ${summary.steps} steps`);
    if (summary.status !== "running") setBadge("status", summary.status, summary.status);
  } catch (err) { /* the table says enough */ }
}

const FONT = "12px sans-serif";  // the plots' words: the page's smallest text is 11 px
const OVERRUNS = 4;  // the task table's column of overruns
const COLOURS = ["#2a62b8", "#d9480f", "#2f9e44", "#7048e8", "#c2255c", "#0b7285", "#e67700", "#5c940d"];

function plotTasks() {
  // Each task's lateness p99 (a line) and the periods it missed since the reading before (a bar), per reading.
  const canvas = $("tasks-plot");
  if (!visible(canvas)) return;
  const wide = Math.max(240, Math.round(canvas.clientWidth));  // drawn at the size shown: text never scaled down
  const ctx = canvas.getContext("2d");
  const h = live.taskHistory;
  if (h.length < 2) { ctx.clearRect(0, 0, canvas.width, canvas.height); return; }
  const names = h[h.length - 1][1].map((x) => x.task);
  const find = (tasks, name) => tasks.find((k) => k.task === name) || {};
  ctx.font = FONT;
  const keys = [];  // each task's name and missed periods, as many to a line as the width takes
  let x = 0, row = 0;
  for (const name of names) {
    const label = `${name} (${find(h[h.length - 1][1], name).missed || 0} missed)`;
    const w = ctx.measureText(label).width;
    if (x && x + w > wide) { x = 0; row += 1; }
    keys.push([label, x, row]);
    x += w + 14;
  }
  const head = 16 * (row + 1) + 6;
  const tall = head + 170;
  if (canvas.width !== wide || canvas.height !== tall) { canvas.width = wide; canvas.height = tall; }
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.font = FONT;  // a canvas resized forgets its font
  let top = 1, most = 1;
  h.forEach(([, tasks], j) => {
    for (const x of tasks) {
      top = Math.max(top, (x.lateness_ms || {}).p99 || 0);
      if (j) most = Math.max(most, x.missed - (find(h[j - 1][1], x.task).missed || 0));
    }
  });
  const left = 64, bottom = canvas.height - 20, height = canvas.height - head - 34;
  const t0 = h[0][0], t1 = h[h.length - 1][0];
  const X = (t) => left + ((t - t0) / Math.max(t1 - t0, 1e-6)) * (canvas.width - left - 8);
  const Y = (v) => bottom - (v / top) * height;
  ctx.fillStyle = "#556";
  ctx.fillText(`p99 ${top.toFixed(1)} ms`, 0, Y(top) + 4);
  ctx.fillText("0", left - 12, bottom);
  ctx.fillText(`bars: missed (most ${most} per reading)`, left, canvas.height - 4);
  names.forEach((name, i) => {
    const colour = COLOURS[i % COLOURS.length];
    ctx.strokeStyle = ctx.fillStyle = colour;
    const [label, kx, krow] = keys[i];
    ctx.fillText(label, kx, 13 + 16 * krow);
    const width = Math.max(1, (canvas.width - left) / h.length / names.length);
    h.forEach(([t, tasks], j) => {
      if (!j) return;
      const missed = (find(tasks, name).missed || 0) - (find(h[j - 1][1], name).missed || 0);
      if (missed > 0) {
        const bar = (missed / most) * height * 0.5;
        ctx.globalAlpha = 0.45;
        ctx.fillRect(X(t) - width * (names.length - i), bottom - bar, width, bar);
        ctx.globalAlpha = 1;
      }
    });
    ctx.beginPath();
    h.forEach(([t, tasks], j) => {
      const v = (find(tasks, name).lateness_ms || {}).p99 || 0;
      if (j) ctx.lineTo(X(t), Y(v)); else ctx.moveTo(X(t), Y(v));
    });
    ctx.stroke();
  });
  canvas.dataset.font = ctx.font;  // what the tests read: the size the plot's words are drawn at
}

// ---- the mission's world ------------------------------------------------------------------------------------------

function drawWorld() {
  const scene = live.scene;
  const canvas = $("world");
  if (!visible(canvas)) return;
  const ctx = canvas.getContext("2d");
  const [x0, y0, x1, y1] = scene.bounds;
  const scale = Math.min((canvas.width - 20) / (x1 - x0), (canvas.height - 20) / (y1 - y0));
  const X = (x) => 10 + (x - x0) * scale;
  const Y = (y) => canvas.height - 10 - (y - y0) * scale;
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  ctx.strokeStyle = "#999";
  ctx.strokeRect(X(x0), Y(y1), (x1 - x0) * scale, (y1 - y0) * scale);
  for (const o of scene.obstacles) {
    ctx.beginPath();
    o.points.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
    if (o.kind === "polygon") { ctx.closePath(); ctx.fillStyle = "#8c8f96"; ctx.fill(); }
    else { ctx.strokeStyle = "#4a4d55"; ctx.lineWidth = 3; ctx.stroke(); ctx.lineWidth = 1; }
  }
  for (const g of scene.goals || []) {
    ctx.fillStyle = "#f0b400";
    ctx.beginPath();
    ctx.arc(X(g.x), Y(g.y), 6, 0, 2 * Math.PI);
    ctx.fill();
  }
  const lines = [];
  live.poses.forEach((pose, i) => {
    const colour = COLOURS[i % COLOURS.length];
    ctx.strokeStyle = colour;
    ctx.lineWidth = 2;
    ctx.beginPath();
    pose.trail.forEach(([x, y], j) => (j ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
    ctx.stroke();
    if (pose.now) {
      const {x, y, theta} = pose.now;
      ctx.fillStyle = colour;
      ctx.beginPath();
      ctx.arc(X(x), Y(y), 5, 0, 2 * Math.PI);
      ctx.fill();
      ctx.beginPath();
      ctx.moveTo(X(x), Y(y));
      ctx.lineTo(X(x + 0.5 * Math.cos(theta)), Y(y + 0.5 * Math.sin(theta)));
      ctx.stroke();
      lines.push(`${pose.poster}${pose.path ? " " + pose.path : ""}: x ${x.toFixed(2)}, y ${y.toFixed(2)}, ` +
                 `θ ${theta.toFixed(2)}`);
    }
  });
  ctx.lineWidth = 1;
  setText($("pose"), lines.join(" · "));
}

watcher.observe($("world"));
watcher.observe($("tasks-plot"));
boot();

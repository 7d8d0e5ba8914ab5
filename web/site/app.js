// The page: forms, previews and downloads. All whycode work happens in
// worker.js (the library compiled to WebAssembly); this file only asks it
// and shows the answers.

const $ = (id) => document.getElementById(id);

// ---------- engine (a worker) ----------

class Engine {
  constructor(name) {
    this.name = name;
    this.next = 1;
    this.pending = new Map();
    this.spawn();
  }

  spawn() {
    this.worker = new Worker(new URL("./worker.js", import.meta.url), { type: "module" });
    this.worker.onmessage = (event) => {
      const { id, ok, result, error, fatal } = event.data;
      const job = this.pending.get(id);
      if (!job) return;
      this.pending.delete(id);
      if (fatal) this.restart("the engine stopped on an internal error");
      if (ok) job.resolve(result);
      else job.reject(new Error(fatal ? `internal error in the whycode engine (${error}); it has been restarted` : error));
    };
    this.worker.onerror = (event) => {
      event.preventDefault();
      this.restart(event.message || "the engine failed to load");
    };
  }

  call(op, args, transfer = []) {
    const id = this.next++;
    if (this.broken) return Promise.reject(new Error(this.broken));
    return new Promise((resolve, reject) => {
      this.pending.set(id, { resolve, reject });
      this.worker.postMessage({ id, op, args }, transfer);
    });
  }

  // Ends whatever runs (a job that takes too long, a crashed engine) and
  // starts a fresh worker; waiting callers get `reason` as their error.
  restart(reason) {
    this.worker.terminate();
    for (const job of this.pending.values()) job.reject(new Error(reason));
    this.pending.clear();
    // A worker that cannot even load would otherwise be restarted forever.
    const now = performance.now();
    this.restarts = (this.restarts || []).filter((t) => now - t < 10000).concat(now);
    if (this.restarts.length > 3) {
      this.broken = `the whycode engine keeps failing (${reason})`;
      return;
    }
    this.spawn();
  }
}

const engine = new Engine("jobs");
let liveEngine = null;

// Runs `work` while `button` shows it is busy; long jobs get a message and
// stay cancellable (ending the worker), so the page never looks frozen.
async function busy(button, msgEl, text, work) {
  const buttons = button ? [button] : [];
  for (const b of buttons) { b.disabled = true; b.classList.add("busy"); }
  let slow = setTimeout(() => showMsg(msgEl, "info", text), 400);
  try {
    return await work();
  } finally {
    clearTimeout(slow);
    for (const b of buttons) { b.disabled = false; b.classList.remove("busy"); }
  }
}

function showMsg(el, kind, text) {
  el.className = `msg ${kind}`;
  el.textContent = text;
}

function clearMsg(el) {
  el.className = "msg";
  el.textContent = "";
}

function download(name, bytes, type) {
  const blob = bytes instanceof Blob ? bytes : new Blob([bytes], { type });
  const url = URL.createObjectURL(blob);
  const a = document.createElement("a");
  a.href = url;
  a.download = name;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

const MIME = { pdf: "application/pdf", svg: "image/svg+xml", png: "image/png", json: "application/json", toml: "application/toml" };
const mimeOf = (name) => MIME[name.split(".").pop()] || "application/octet-stream";

function debounce(fn, ms) {
  let timer = null;
  return (...args) => { clearTimeout(timer); timer = setTimeout(() => fn(...args), ms); };
}

const intOf = (el) => {
  const v = Number(el.value);
  return Number.isInteger(v) ? v : NaN;
};

// ---------- tabs ----------

function showPanel(name) {
  for (const tab of document.querySelectorAll(".tabs button")) {
    tab.setAttribute("aria-selected", String(tab.dataset.panel === name));
  }
  for (const panel of document.querySelectorAll(".panel")) {
    panel.hidden = panel.id !== `panel-${name}`;
  }
  if (location.hash !== `#${name}`) history.replaceState(null, "", `#${name}`);
  if (name === "print") printPreview();
}

for (const tab of document.querySelectorAll(".tabs button")) {
  tab.addEventListener("click", () => showPanel(tab.dataset.panel));
}

// ---------- IDs ----------

const TABLE_ROWS = 1000;
const COUNT_BITS = [4, 6, 8, 10, 12, 14, 16];
const COUNT_DISTANCES = [1, 2, 3, 4];
let idsRequest = 0;

async function idsUpdate() {
  const msg = $("ids-msg");
  const bits = intOf($("ids-bits"));
  const distance = intOf($("ids-distance"));
  const mine = ++idsRequest;
  $("ids-cli").textContent = `whycode ids --bits ${$("ids-bits").value} --distance ${$("ids-distance").value} --format json`;
  markCount(bits, distance);
  if (!(bits >= 2 && bits <= 24) || !(distance >= 1 && distance <= bits)) {
    showMsg(msg, "error", !(bits >= 2 && bits <= 24)
      ? "Bits must be a whole number from 2 to 24."
      : `Distance must be a whole number from 1 to the bit count (${bits}).`);
    $("ids-download").disabled = true;
    return;
  }
  $("ids-download").disabled = false;
  try {
    const family = await busy(null, msg, `Generating the ${bits}-bit family…`, () =>
      engine.call("familyTable", { bits, distance, limit: TABLE_ROWS }));
    if (mine !== idsRequest) return;
    clearMsg(msg);
    const min = family.min_distance == null ? "– (a single ID)" : family.min_distance;
    $("ids-summary").innerHTML = `<strong>${family.len.toLocaleString("en")}</strong> IDs · minimum distance ${min} · worst self-distance ${family.worst_self_distance ?? "–"}`;
    $("ids-table-title").textContent = `IDs of the ${bits}-bit, distance-${distance} family`;
    const rows = family.rows.map(([id, code, binary, sd]) =>
      `<tr><td>${id}</td><td>${code}</td><td class="text mono">${binary}</td><td>${sd}</td></tr>`).join("");
    $("ids-table").innerHTML = `<thead><tr><th>ID</th><th>Code</th><th class="text">Binary</th><th>Self-distance</th></tr></thead><tbody>${rows}</tbody>`;
    $("ids-more").textContent = family.len > family.rows.length
      ? `Showing the first ${family.rows.length.toLocaleString("en")} of ${family.len.toLocaleString("en")} IDs; the JSON file has them all.`
      : "";
  } catch (err) {
    if (mine === idsRequest) showMsg(msg, "error", err.message);
  }
}

function markCount(bits, distance) {
  for (const td of document.querySelectorAll("#counts td[data-bits]")) {
    td.classList.toggle("sel", Number(td.dataset.bits) === bits && Number(td.dataset.distance) === distance);
  }
}

async function idsCounts() {
  try {
    const m = await engine.call("counts", { bits: COUNT_BITS, distances: COUNT_DISTANCES });
    let html = `<thead><tr><th>d \\ bits</th>${m.bits.map((n) => `<th>${n}</th>`).join("")}</tr></thead><tbody>`;
    m.counts.forEach((row, k) => {
      const d = m.distances[k];
      html += `<tr><th>${d}</th>${row.map((c, j) => c == null
        ? `<td class="none">–</td>`
        : `<td data-bits="${m.bits[j]}" data-distance="${d}" title="${m.bits[j]} bits, distance ${d}">${c.toLocaleString("en")}</td>`).join("")}</tr>`;
    });
    $("counts").innerHTML = html + "</tbody>";
    markCount(intOf($("ids-bits")), intOf($("ids-distance")));
  } catch (err) {
    showMsg($("ids-msg"), "error", err.message);
  }
}

$("counts").addEventListener("click", (event) => {
  const td = event.target.closest("td[data-bits]");
  if (!td) return;
  $("ids-bits").value = td.dataset.bits;
  $("ids-distance").value = td.dataset.distance;
  idsUpdate();
});
const idsLater = debounce(idsUpdate, 250);
$("ids-bits").addEventListener("input", idsLater);
$("ids-distance").addEventListener("input", idsLater);
$("ids-download").addEventListener("click", async (event) => {
  const bits = intOf($("ids-bits"));
  const distance = intOf($("ids-distance"));
  try {
    const text = await busy(event.currentTarget, $("ids-msg"), "Generating…", () =>
      engine.call("familyJson", { bits, distance }));
    clearMsg($("ids-msg"));
    download(`family-${bits}b-d${distance}.json`, text, MIME.json);
  } catch (err) {
    showMsg($("ids-msg"), "error", err.message);
  }
});

// ---------- Print ----------

let templates = [];
let previewPages = [];
let previewPage = 0;
let previewRequest = 0;

const printKind = () => document.querySelector("input[name=print-kind]:checked").value;
const printLegacy = () => document.querySelector("input[name=print-style]:checked").value === "legacy";

function fillTemplates(list) {
  templates = list;
  $("p-template").innerHTML = list.map((t) =>
    `<option value="${t.name}">${t.name.toUpperCase()} — ${t.description.replace(/^.*?,\s*/, "")}</option>`).join("");
  $("p-template").value = "a4";
  resetLayout();
}

// The custom-layout fields start at the chosen template's values.
function resetLayout() {
  const t = templates.find((x) => x.name === $("p-template").value);
  if (!t) return;
  $("p-label-pt").value = t.label_size_pt;
  $("p-scale-bar").value = t.scale_bar_mm;
  $("p-margin-sheet").value = t.margin_mm;
  $("p-gap").value = t.gap_mm;
  $("p-cut-guides").checked = t.cut_guides;
}

const fmt = (v) => String(Number(v.toFixed(6)));

// A custom template when the layout fields differ from the built-in one:
// its TOML text (downloaded with the sheet) and the name the CLI would
// record, the file's name.
function customTemplate() {
  const t = templates.find((x) => x.name === $("p-template").value);
  if (!t) return null;
  const fields = {
    label: Number($("p-label-pt").value),
    bar: Number($("p-scale-bar").value),
    margin: Number($("p-margin-sheet").value),
    gap: Number($("p-gap").value),
    cut: $("p-cut-guides").checked,
  };
  if (fields.label === t.label_size_pt && fields.bar === t.scale_bar_mm && fields.margin === t.margin_mm &&
      fields.gap === t.gap_mm && fields.cut === t.cut_guides) return null;
  for (const [k, v] of Object.entries(fields)) {
    if (k !== "cut" && !(Number.isFinite(v) && v >= 0)) throw new Error(`the ${k === "bar" ? "scale bar" : k} must be a number`);
  }
  const name = `${t.name}-custom.toml`;
  const toml = [
    `# ${t.description}, with the layout changed in the whycode page`,
    `description = ${JSON.stringify(t.description)}`,
    `page_width = "${fmt(t.width_mm)}mm"`,
    `page_height = "${fmt(t.height_mm)}mm"`,
    `margin = "${fmt(fields.margin)}mm"`,
    `gap = "${fmt(fields.gap)}mm"`,
    `label_size_pt = ${Number.isInteger(fields.label) ? fields.label.toFixed(1) : String(fields.label)}`,
    `cut_guides = ${fields.cut}`,
    `scale_bar = "${fmt(fields.bar)}mm"`,
    "",
  ].join("\n");
  return { name, toml };
}

function printOptions(format, check) {
  const kind = printKind();
  const legacy = printLegacy();
  const name = ($("p-name").value.trim() || (kind === "sheet" ? "swarm" : "marker")).replace(/[\\/:*?"<>|]/g, "_");
  const diameter = `${$("p-diameter").value.trim()}${$("p-unit").value}`;
  const dpi = Number($("p-dpi").value);
  const output = `${name}.${format}`;
  const bits = intOf($("p-bits"));
  const distance = intOf($("p-distance"));
  const whole = (el, what) => {
    if (!Number.isInteger(Number(el.value)) || el.value.trim() === "") throw new Error(`${what} must be a whole number.`);
  };
  if (!legacy) { whole($("p-bits"), "Bits"); whole($("p-distance"), "Distance"); }
  if (!legacy && kind === "marker") whole($("p-id"), "The ID");
  if (legacy && kind === "sheet") whole($("p-count"), "The number of circles");
  if (format === "png" && !Number.isFinite(dpi)) throw new Error("PNG dpi must be a number.");
  const cli = [`whycode ${kind}`];
  const extra = { custom: null };
  let options;
  if (kind === "sheet") {
    const custom = customTemplate();
    options = {
      diameter, output, dpi, no_check: !check,
      template: custom ? custom.name : $("p-template").value,
      template_toml: custom ? custom.toml : null,
    };
    if (legacy) {
      options.legacy = true;
      options.count = intOf($("p-count"));
      cli.push(`--legacy --count ${$("p-count").value}`);
    } else {
      Object.assign(options, { bits, distance, ids: $("p-ids").value.trim() || null });
      cli.push(`--bits ${bits} --distance ${distance}`);
      cli.push(options.ids ? `--ids ${options.ids.replace(/\s+/g, "")}` : "--all");
    }
    cli.push(`--diameter ${diameter} --template ${options.template}`);
    extra.custom = custom;
  } else {
    options = {
      diameter, output, dpi, no_check: !check,
      cross: $("p-cross").checked, cut_guide: $("p-cut").checked, label: $("p-label").checked,
      margin: $("p-margin").value.trim() || null,
    };
    if (legacy) {
      options.legacy = true;
      cli.push("--legacy");
    } else {
      Object.assign(options, { bits, distance, id: intOf($("p-id")) });
      cli.push(`--bits ${bits} --distance ${distance} --id ${$("p-id").value}`);
    }
    cli.push(`--diameter ${diameter}`);
    if (options.margin) cli.push(`--margin ${options.margin}`);
    if (options.label) cli.push("--label");
    if (options.cross) cli.push("--cross");
    if (options.cut_guide) cli.push("--cut-guide");
  }
  if (format === "png" && dpi !== 300) cli.push(`--dpi ${$("p-dpi").value}`);
  cli.push(`-o ${output}`);
  return { options, kind, cli: cli.join(" "), custom: extra.custom };
}

function syncPrintForm() {
  const kind = printKind();
  const legacy = printLegacy();
  const show = (selector, visible) => {
    for (const el of document.querySelectorAll(selector)) el.hidden = !visible;
  };
  show(".sheet-only", kind === "sheet");
  show(".marker-only", kind === "marker");
  show(".whycode-only", !legacy);
  show(".legacy-only", legacy);
  // Elements in both groups need both conditions.
  for (const el of document.querySelectorAll(".whycode-only.sheet-only")) el.hidden = legacy || kind !== "sheet";
  for (const el of document.querySelectorAll(".whycode-only.marker-only")) el.hidden = legacy || kind !== "marker";
  for (const el of document.querySelectorAll(".legacy-only.sheet-only")) el.hidden = !legacy || kind !== "sheet";
  const name = $("p-name");
  if (kind === "sheet" && name.value === "marker") name.value = "swarm";
  if (kind === "marker" && name.value === "swarm") name.value = "marker";
}

async function printPreview() {
  if ($("panel-print").hidden) return;
  syncPrintForm();
  const mine = ++previewRequest;
  const msg = $("print-msg");
  let request;
  try {
    request = printOptions("svg", false);
  } catch (err) {
    showMsg(msg, "error", err.message);
    return;
  }
  $("print-cli").textContent = printOptions("pdf", true).cli;
  try {
    const out = await busy(null, msg, "Laying out…", () =>
      engine.call(request.kind, request.options));
    if (mine !== previewRequest) return;
    clearMsg(msg);
    for (const url of previewPages) URL.revokeObjectURL(url);
    previewPages = out.files.filter((f) => f.name.endsWith(".svg"))
      .map((f) => URL.createObjectURL(new Blob([f.bytes], { type: MIME.svg })));
    previewPage = Math.min(previewPage, previewPages.length - 1);
    showPreviewPage();
    const last = out.notes.split("\n").pop();
    $("print-info").textContent = request.kind === "sheet" ? last : "";
  } catch (err) {
    if (mine === previewRequest) {
      showMsg(msg, "error", err.message);
      $("print-preview").classList.add("stale");
    }
  }
}

function showPreviewPage() {
  const box = $("print-preview");
  box.classList.toggle("marker", printKind() === "marker");
  box.classList.remove("stale");
  box.innerHTML = "";
  const img = document.createElement("img");
  img.alt = `Preview of page ${previewPage + 1}`;
  img.src = previewPages[previewPage];
  box.appendChild(img);
  $("print-pager").hidden = previewPages.length < 2;
  $("pg-label").textContent = `page ${previewPage + 1} of ${previewPages.length}`;
}

$("pg-prev").addEventListener("click", () => { previewPage = Math.max(0, previewPage - 1); showPreviewPage(); });
$("pg-next").addEventListener("click", () => { previewPage = Math.min(previewPages.length - 1, previewPage + 1); showPreviewPage(); });

const previewLater = debounce(printPreview, 300);
$("print-form").addEventListener("input", (event) => {
  if (event.target.id === "p-template") resetLayout();
  previewLater();
});
$("print-form").addEventListener("change", (event) => {
  if (event.target.id === "p-template") { resetLayout(); previewLater(); }
  if (event.target.name === "print-kind" || event.target.name === "print-style") { previewPage = 0; printPreview(); }
});

async function printDownload(button, format, manifestOnly) {
  const msg = $("print-msg");
  let request;
  try {
    request = printOptions(format, true);
  } catch (err) {
    showMsg(msg, "error", err.message);
    return;
  }
  try {
    const out = await busy(button, msg, "Rendering and reading every marker back (the self-check)…", () =>
      engine.call(request.kind, request.options));
    const wanted = manifestOnly ? out.files.filter((f) => f.name.endsWith(".json")) : out.files.filter((f) => !f.name.endsWith(".json"));
    for (const f of wanted) download(f.name, f.bytes, mimeOf(f.name));
    if (manifestOnly && request.custom) {
      download(request.custom.name, new TextEncoder().encode(request.custom.toml), MIME.toml);
    }
    const written = wanted.map((f) => f.name).join(", ");
    showMsg(msg, "ok", `${out.notes.split("\n")[0]}. Saved ${written}.${request.kind === "sheet" && !manifestOnly ? " Keep the manifest too: the Check tab needs it." : ""}`);
  } catch (err) {
    showMsg(msg, "error", err.message);
  }
}

// The manifest names the page files it was written with (and their
// digests), as `whycode sheet` writes it beside them: it belongs to the
// format downloaded last. Before any download, SVG's (no PDF module needed).
let lastSheetFormat = "svg";
for (const button of document.querySelectorAll("#print-form button[data-format]")) {
  button.addEventListener("click", () => {
    lastSheetFormat = button.dataset.format;
    printDownload(button, button.dataset.format, false);
  });
}
$("p-manifest").addEventListener("click", (event) => printDownload(event.currentTarget, lastSheetFormat, true));

// ---------- Check ----------

const MAX_PHOTO_BYTES = 80 * 1024 * 1024;
const MAX_MANIFEST_BYTES = 20 * 1024 * 1024;
let checkPhotos = [];
let checkReport = null;

function listPhotos() {
  $("c-list").innerHTML = checkPhotos.map((f) =>
    `<li><span>${escapeHtml(f.name)}</span><span>${(f.size / 1e6).toFixed(1)} MB</span></li>`).join("");
  const manifest = $("c-manifest").files[0];
  $("check-cli").textContent = `whycode validate --manifest ${manifest ? manifest.name : "SHEET.json"} ${checkPhotos.length ? checkPhotos.map((f) => f.name).join(" ") : "PHOTO…"} --format json`;
}

function escapeHtml(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;", "'": "&#39;" }[c]));
}

function addPhotos(input) {
  const msg = $("check-msg");
  clearMsg(msg);
  for (const file of input.files) {
    if (file.size > MAX_PHOTO_BYTES) {
      showMsg(msg, "error", `${file.name}: ${(file.size / 1e6).toFixed(0)} MB is too large a file for the page (at most ${MAX_PHOTO_BYTES / 1e6} MB); scale the photo down or use the whycode command.`);
      continue;
    }
    checkPhotos.push(file);
  }
  input.value = "";
  listPhotos();
}
$("c-camera").addEventListener("change", (e) => addPhotos(e.target));
$("c-photos").addEventListener("change", (e) => addPhotos(e.target));
$("c-manifest").addEventListener("change", () => { clearMsg($("check-msg")); listPhotos(); });
$("c-clear").addEventListener("click", () => {
  checkPhotos = [];
  checkReport = null;
  $("c-manifest").value = "";
  for (const id of ["c-verdict", "c-pages", "c-markers", "c-table", "c-photos-out"]) $(id).innerHTML = "";
  $("c-verdict").className = "verdict";
  $("c-download").disabled = true;
  clearMsg($("check-msg"));
  listPhotos();
});
$("c-download").addEventListener("click", () => {
  if (checkReport) download("report.json", checkReport, MIME.json);
});

// A photo check that has not answered after this long is ended, and the
// engine restarted, rather than leave the page waiting without end.
const PHOTO_TIMEOUT_MS = 120000;

function withTimeout(promise, ms, what) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => {
      engine.restart(`${what} took longer than ${ms / 1000} s and was stopped`);
      reject(new Error(`${what} took longer than ${ms / 1000} s and was stopped`));
    }, ms);
  });
  return Promise.race([promise, timeout]).finally(() => clearTimeout(timer));
}

$("c-run").addEventListener("click", async (event) => {
  const msg = $("check-msg");
  const button = event.currentTarget;
  const manifestFile = $("c-manifest").files[0];
  if (!manifestFile) { showMsg(msg, "error", "Choose the sheet's manifest (the .json file saved with the sheet) first."); return; }
  if (!checkPhotos.length) { showMsg(msg, "error", "Add at least one photo of the printed sheet."); return; }
  if (manifestFile.size > MAX_MANIFEST_BYTES) { showMsg(msg, "error", `${manifestFile.name}: too large to be a sheet manifest.`); return; }
  button.disabled = true;
  button.classList.add("busy");
  $("c-photos-out").innerHTML = "";
  try {
    const text = await manifestFile.text();
    await engine.call("validateStart", { name: manifestFile.name, text });
    const out = $("c-photos-out");
    let k = 0;
    for (const photo of checkPhotos) {
      k++;
      showMsg(msg, "info", `Checking ${photo.name} (${k} of ${checkPhotos.length})…`);
      const bytes = await photo.arrayBuffer();
      const png = await withTimeout(engine.call("validatePhoto", { name: photo.name, bytes }, [bytes]), PHOTO_TIMEOUT_MS, `Checking ${photo.name}`);
      const url = URL.createObjectURL(new Blob([png], { type: MIME.png }));
      const stem = photo.name.replace(/\.[^.]*$/, "");
      const fig = document.createElement("figure");
      fig.innerHTML = `<img alt="${escapeHtml(photo.name)} with the markers marked"><figcaption><span>${escapeHtml(photo.name)}</span><a download="${escapeHtml(stem)}.annotated.png">Download</a></figcaption>`;
      fig.querySelector("img").src = url;
      fig.querySelector("a").href = url;
      out.appendChild(fig);
    }
    const report = await engine.call("validateReport", {});
    checkReport = report.json;
    showReport(JSON.parse(report.json), report.table);
    clearMsg(msg);
    $("c-download").disabled = false;
  } catch (err) {
    showMsg(msg, "error", err.message);
  } finally {
    button.disabled = false;
    button.classList.remove("busy");
  }
});

function showReport(r, table) {
  const c = r.counts;
  const verdict = $("c-verdict");
  verdict.className = `verdict ${r.ok ? "ok" : "bad"}`;
  verdict.innerHTML = `${r.ok ? "✓ Every marker printed and reads as its own ID" : "✗ The sheet has problems"}
    <div class="counts"><span>${c.printed} printed</span><span>${c.found} found</span><span>${c.misread} misread</span><span>${c.unidentified} unidentified</span><span>${c.missing} missing</span></div>`;
  $("c-pages").innerHTML = `<thead><tr><th>Page</th><th class="text">Printed scale</th><th class="text">Note</th></tr></thead><tbody>${r.pages.map((p) => {
    const scale = p.scale == null ? "unknown" : `${(p.scale * 100).toFixed(1)} %`;
    return `<tr><td>${p.page}</td><td class="text ${p.scale_status}">${scale} (${p.scale_status})</td><td class="text wrap">${escapeHtml(p.note || "")}</td></tr>`;
  }).join("")}</tbody>`;
  $("c-markers").innerHTML = `<thead><tr><th>ID</th><th>Page</th><th class="text">Status</th><th>Read as</th><th class="text">Photo</th></tr></thead><tbody>${r.markers.map((m) =>
    `<tr><td>${m.id}</td><td>${m.page}</td><td class="text ${m.status}">${m.status}</td><td>${m.read_as ?? ""}</td><td class="text">${escapeHtml(m.photo || "")}</td></tr>`).join("")}</tbody>`;
  $("c-table").textContent = table;
}

// ---------- Calibrate ----------

// The photos in the engine's calibration, in order: { name, size, markers }.
let calPhotos = [];
// The manifest the engine's calibration was started with (a File).
let calManifest = null;
let calCamera = null;

const CAMERA_FILE = "camera.yaml";

// One calibration step at a time: a manifest chosen while photos are still
// being read (or the other way round) waits for the step before it.
let calQueue = Promise.resolve();
function calSerial(step) {
  const next = calQueue.then(step, step);
  calQueue = next.catch(() => {});
  return next;
}

function calOptions() {
  return {
    fix_principal_point: $("cal-fix-pp").checked,
    fix_aspect: $("cal-fix-aspect").checked,
    no_tangential: $("cal-no-tangential").checked,
    no_k3: $("cal-no-k3").checked,
    print_scale: $("cal-scale").value.trim() || null,
  };
}

function calFlags() {
  const o = calOptions();
  return [o.fix_principal_point && "--fix-principal-point", o.fix_aspect && "--fix-aspect",
    o.no_tangential && "--no-tangential", o.no_k3 && "--no-k3",
    o.print_scale && `--print-scale ${o.print_scale}`].filter(Boolean).join(" ");
}

function calList() {
  $("cal-list").innerHTML = calPhotos.map((p, k) =>
    `<li><span>${escapeHtml(p.name)}</span><span>${p.markers} marker${p.markers === 1 ? "" : "s"}</span><button type="button" class="remove" data-index="${k}" aria-label="Remove ${escapeHtml(p.name)}">×</button></li>`).join("");
  const names = calPhotos.length ? calPhotos.map((p) => p.name).join(" ") : "PHOTO…";
  const flags = calFlags();
  $("cal-cli").textContent = `whycode calibrate --manifest ${calManifest ? calManifest.name : "SHEET.json"} ${names}${flags ? ` ${flags}` : ""} -o ${CAMERA_FILE}`;
}

function calForget() {
  calCamera = null;
  $("cal-download").disabled = true;
  $("cal-table").textContent = "";
}

function showCoverage(counts) {
  const rows = counts || [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  $("cal-coverage").innerHTML = `<tbody>${rows.map((row) =>
    `<tr>${row.map((n) => `<td class="${n ? "" : "empty"}">${n}</td>`).join("")}</tr>`).join("")}</tbody>`;
}

// Coverage and a first fit over the photos so far (the calibration itself
// re-reads the centres through the camera it finds, and ends lower).
async function calPreview() {
  if (!calManifest || !calPhotos.length) {
    showCoverage(null);
    $("cal-fit").textContent = calPhotos.length ? "" : "Add photos to see which parts of the image they cover.";
    $("cal-advice").innerHTML = "";
    return;
  }
  try {
    const p = await engine.call("calibratePreview", { options: calOptions() });
    showCoverage(p.coverage);
    const views = p.views.length;
    if (p.fit.refusal) {
      $("cal-fit").textContent = `${views} view${views === 1 ? "" : "s"} of the sheet; no fit yet: ${p.fit.refusal}`;
      $("cal-advice").innerHTML = "";
    } else {
      $("cal-fit").textContent = `${views} views; first fit (on the ellipses' centres): RMS ${p.fit.rms_px.toFixed(3)} px, fx ${p.fit.fx.toFixed(1)}, fy ${p.fit.fy.toFixed(1)}`;
      $("cal-advice").innerHTML = p.fit.advice.map((a) => `<li>${escapeHtml(a)}</li>`).join("");
    }
  } catch (err) {
    showMsg($("cal-msg"), "error", err.message);
  }
}

// Starts the engine's calibration for the chosen manifest and reads every
// listed photo into it again.
async function calStart() {
  const file = $("cal-manifest").files[0];
  if (!file) return false;
  if (file.size > MAX_MANIFEST_BYTES) throw new Error(`${file.name}: too large to be a sheet manifest.`);
  await engine.call("calibrateStart", { name: file.name, text: await file.text() });
  calManifest = file;
  const files = calPhotos.map((p) => p.file);
  calPhotos = [];
  for (const f of files) await calAddOne(f);
  return true;
}

async function calAddOne(file) {
  const bytes = await file.arrayBuffer();
  const markers = await withTimeout(engine.call("calibratePhoto", { name: file.name, bytes }, [bytes]),
    PHOTO_TIMEOUT_MS, `Reading ${file.name}`);
  calPhotos.push({ name: file.name, size: file.size, markers, file });
}

async function calAddPhotos(files) {
  const msg = $("cal-msg");
  clearMsg(msg);
  try {
    if (!calManifest && !(await calStart())) {
      showMsg(msg, "error", "Choose the sheet's manifest (the .json file saved with the sheet) first.");
      return;
    }
    let k = 0;
    for (const file of files) {
      k++;
      if (file.size > MAX_PHOTO_BYTES) {
        showMsg(msg, "error", `${file.name}: ${(file.size / 1e6).toFixed(0)} MB is too large a file for the page (at most ${MAX_PHOTO_BYTES / 1e6} MB); scale the photo down or use the whycode command.`);
        continue;
      }
      showMsg(msg, "info", `Reading ${file.name} (${k} of ${files.length})…`);
      await calAddOne(file);
      calForget();
      calList();
      await calPreview();
    }
    if (msg.classList.contains("info")) clearMsg(msg);
  } catch (err) {
    showMsg(msg, "error", err.message);
  }
  calList();
}

function calPhotosChosen(input) {
  // The files are taken now: the input is cleared for the next choice.
  const files = [...input.files];
  input.value = "";
  calSerial(() => calAddPhotos(files));
}
$("cal-camera").addEventListener("change", (e) => calPhotosChosen(e.target));
$("cal-photos").addEventListener("change", (e) => calPhotosChosen(e.target));
$("cal-manifest").addEventListener("change", () => calSerial(async () => {
  const msg = $("cal-msg");
  clearMsg(msg);
  calForget();
  calManifest = null;
  try {
    await calStart();
  } catch (err) {
    calManifest = null;
    showMsg(msg, "error", err.message);
  }
  calList();
  await calPreview();
}));
$("cal-list").addEventListener("click", (e) => {
  const button = e.target.closest("button.remove");
  if (!button) return;
  const index = Number(button.dataset.index);
  calSerial(async () => {
    calPhotos.splice(index, 1);
    await engine.call("calibrateRemove", { index });
    calForget();
    calList();
    await calPreview();
  });
});
for (const id of ["cal-fix-pp", "cal-fix-aspect", "cal-no-tangential", "cal-no-k3", "cal-scale"]) {
  $(id).addEventListener(id === "cal-scale" ? "input" : "change", debounce(() => { calForget(); calList(); calPreview(); }, 300));
}
$("cal-clear").addEventListener("click", () => {
  calPhotos = [];
  calManifest = null;
  $("cal-manifest").value = "";
  calForget();
  clearMsg($("cal-msg"));
  calList();
  calPreview();
});
$("cal-download").addEventListener("click", () => {
  if (calCamera) download(CAMERA_FILE, calCamera, "application/x-yaml");
});

// Each photo's markers are read once more per round, through the camera
// found so far: allow for a few rounds of every photo.
const CALIBRATE_TIMEOUT_MS = 600000;

$("cal-run").addEventListener("click", (event) => {
  const button = event.currentTarget;
  calSerial(() => calRun(button));
});

async function calRun(button) {
  const msg = $("cal-msg");
  if (!calManifest) { showMsg(msg, "error", "Choose the sheet's manifest (the .json file saved with the sheet) first."); return; }
  if (!calPhotos.length) { showMsg(msg, "error", "Add photos of the printed sheet: 10-20, tilted different ways."); return; }
  calForget();
  button.disabled = true;
  button.classList.add("busy");
  showMsg(msg, "info", `Calibrating from ${calPhotos.length} photo${calPhotos.length === 1 ? "" : "s"} (the markers are read again through each camera found until it settles)…`);
  try {
    const out = await withTimeout(engine.call("calibrateRun", { options: calOptions(), output: CAMERA_FILE }),
      CALIBRATE_TIMEOUT_MS, "The calibration");
    const r = JSON.parse(out.json);
    calCamera = out.camera;
    $("cal-table").textContent = out.table;
    const p = Object.fromEntries(r.parameters.map((q) => [q.name, q]));
    const sd = (q) => (q.std_dev == null ? "held" : `± ${q.std_dev.toPrecision(2)}`);
    $("cal-fit").textContent = `Calibrated from ${r.views.length} views: RMS ${r.rms_px.toFixed(3)} px; fx ${p.fx.value.toFixed(2)} ${sd(p.fx)}, fy ${p.fy.value.toFixed(2)} ${sd(p.fy)}, cx ${p.cx.value.toFixed(2)} ${sd(p.cx)}, cy ${p.cy.value.toFixed(2)} ${sd(p.cy)}, k1 ${p.k1.value.toFixed(4)}`;
    $("cal-advice").innerHTML = r.advice.map((a) => `<li>${escapeHtml(a)}</li>`).join("");
    showCoverage(r.coverage);
    $("cal-download").disabled = false;
    showMsg(msg, "ok", `Done: download ${CAMERA_FILE} for whycode detect --camera.`);
  } catch (err) {
    showMsg(msg, "error", err.message);
  } finally {
    button.disabled = false;
    button.classList.remove("busy");
  }
}

// ---------- Live ----------

const live = { stream: null, running: false, stride: 11, frames: 0, t0: 0, ms: 0, seen: new Map(), framed: false, shown: 0 };

// The detector's options as the binding takes them (web/src/lib.rs,
// LiveOptions): the marker kind and the frames of reference, files as
// {name, text}.
async function liveOptions() {
  const legacy = document.querySelector("input[name=live-style]:checked").value === "legacy";
  const upload = async (file) => ({ name: file.name, text: await file.text() });
  const camera = $("l-camera-file").files[0];
  const arena = $("l-arena").files[0];
  const diameter = $("l-diameter").value.trim();
  return {
    legacy,
    bits: legacy ? null : intOf($("l-bits")),
    distance: legacy ? null : intOf($("l-distance")),
    diameter: diameter || null,
    camera: camera ? await upload(camera) : null,
    boards: await Promise.all([...$("l-boards").files].map(upload)),
    arena: arena ? await upload(arena) : null,
  };
}

// The command line that gives the same numbers for a photo.
function liveCli(options, photo) {
  const words = ["whycode", "detect"];
  if (options.legacy) words.push("--legacy");
  else words.push("--bits", options.bits, "--distance", options.distance);
  if (options.camera) words.push("--camera", options.camera.name);
  if (options.diameter) words.push("--diameter", options.diameter);
  for (const b of options.boards) words.push("--board", b.name);
  if (options.arena) words.push("--arena", options.arena.name);
  words.push("--format", "json", photo);
  return words.join(" ");
}

// "-0.0000" reads as a sign that is not there.
const fixed = (x, digits) => (x === null || x === undefined || Number.isNaN(x) ? "–" : x.toFixed(digits).replace(/^-(0\.?0*)$/, "$1"));
const degrees = (rad, digits = 1) => (rad === null || rad === undefined ? "–" : ((rad * 180) / Math.PI).toFixed(digits));

// A frame as `whycode detect --format json` writes it: each marker's ID
// with its arena place (or its pose), and each board's pose.
function showFrame(frame) {
  $("l-results").hidden = false;
  const markers = [...frame.markers].sort((a, b) => (a.id === 0) - (b.id === 0) || a.id - b.id || a.u - b.u);
  const arena = markers.some((m) => m.arena);
  const pose = markers.some((m) => m.position);
  const head = ["ID", "u", "v", "yaw°"];
  if (pose) head.push("x m", "y m", "z m");
  if (arena) head.push("arena x m", "arena y m", "arena yaw°");
  const rows = markers.map((m) => {
    const cells = [m.id || "?", fixed(m.u, 1), fixed(m.v, 1), degrees(m.yaw)];
    if (pose) cells.push(...(m.position ? m.position.map((x) => fixed(x, 3)) : ["–", "–", "–"]));
    if (arena) cells.push(...(m.arena ? [fixed(m.arena.x, 4), fixed(m.arena.y, 4), degrees(m.arena.yaw, 2)] : ["–", "–", "–"]));
    return cells;
  });
  table($("l-markers"), head, rows);
  $("l-markers").dataset.ids = markers.map((m) => m.id).join(",");
  const boards = frame.boards || [];
  table($("l-boards-table"), ["board", "x m", "y m", "z m", "quaternion x, y, z, w", "markers used / seen", "rejected", "RMS px"],
    boards.map((b) => [b.name, ...b.position.map((x) => fixed(x, 4)), b.quaternion.map((q) => fixed(q, 4)).join(", "),
      `${b.used.length} / ${b.seen.length}`, b.rejected.join(", ") || "–", fixed(b.rms_px, 3)]));
  $("l-boards-table").hidden = boards.length === 0;
  $("l-results-title").textContent = `${frame.image}: ${markers.length} marker${markers.length === 1 ? "" : "s"}${boards.length ? `, ${boards.length} board pose${boards.length === 1 ? "" : "s"}` : ""}`;
}

function table(el, head, rows) {
  el.replaceChildren();
  const tr = document.createElement("tr");
  for (const h of head) {
    const th = document.createElement("th");
    th.textContent = h;
    tr.append(th);
  }
  el.append(tr);
  for (const row of rows) {
    const r = document.createElement("tr");
    row.forEach((c, k) => {
      const td = document.createElement("td");
      if (k === 0) td.className = "text";
      td.textContent = c;
      r.append(td);
    });
    el.append(r);
  }
}

async function livePhoto(input) {
  const msg = $("live-msg");
  const file = input.files[0];
  input.value = "";
  if (!file) return;
  clearMsg(msg);
  if (!liveEngine) liveEngine = new Engine("live");
  try {
    const options = await liveOptions();
    const bytes = await file.arrayBuffer();
    const json = await liveEngine.call("livePhoto", { options, name: file.name, bytes }, [bytes]);
    $("l-json").textContent = json;
    $("l-cli").textContent = liveCli(options, file.name);
    showFrame(JSON.parse(json));
  } catch (err) {
    showMsg(msg, "error", err.message);
  }
}

async function liveStart() {
  const msg = $("live-msg");
  clearMsg(msg);
  const [width, height] = $("l-size").value.split("x").map(Number);
  if (!navigator.mediaDevices || !navigator.mediaDevices.getUserMedia) {
    showMsg(msg, "error", "This browser gives the page no camera (a camera needs https or localhost).");
    return;
  }
  if (!liveEngine) liveEngine = new Engine("live");
  try {
    const options = await liveOptions();
    // Board poses and arena places come as the frame's JSON, only when asked for.
    live.framed = options.boards.length > 0 || options.arena !== null || options.camera !== null;
    live.stride = await liveEngine.call("liveStart", { options });
  } catch (err) {
    showMsg(msg, "error", err.message);
    return;
  }
  try {
    live.stream = await navigator.mediaDevices.getUserMedia({
      video: { width: { ideal: width }, height: { ideal: height }, facingMode: "environment" },
      audio: false,
    });
  } catch (err) {
    showMsg(msg, "error", err.name === "NotAllowedError"
      ? "The camera was not allowed: allow it in the browser's site settings and start again."
      : `No camera: ${err.message || err.name}`);
    return;
  }
  const video = $("l-video");
  video.srcObject = live.stream;
  await video.play();
  $("l-placeholder").hidden = true;
  $("l-start").disabled = true;
  $("l-stop").disabled = false;
  live.running = true;
  live.frames = 0;
  live.t0 = performance.now();
  live.seen.clear();
  liveLoop();
}

function liveStop() {
  live.running = false;
  if (live.stream) for (const t of live.stream.getTracks()) t.stop();
  live.stream = null;
  $("l-video").srcObject = null;
  $("l-start").disabled = false;
  $("l-stop").disabled = true;
  $("l-placeholder").hidden = false;
  const overlay = $("l-overlay");
  overlay.getContext("2d").clearRect(0, 0, overlay.width, overlay.height);
}

// One frame in flight at a time: wait for a new camera frame, detect in
// the worker, then draw that very frame with its markers (so the outlines
// never lag behind a moving picture). The rate shown is camera frames
// detected per second over the last second; the time per frame is the
// detector's own, which says how much faster a faster camera could go.
function nextVideoFrame(video) {
  return new Promise((resolve) => {
    if (video.requestVideoFrameCallback) video.requestVideoFrameCallback(() => resolve());
    else requestAnimationFrame(() => resolve());
  });
}

async function liveLoop() {
  const video = $("l-video");
  const grab = document.createElement("canvas");
  const gctx = grab.getContext("2d", { willReadFrequently: true });
  const overlay = $("l-overlay");
  const octx = overlay.getContext("2d");
  let windowStart = performance.now();
  let windowFrames = 0;
  let lastFrameTime = -1;
  // Every frame the browser presents, detected or not: the camera's own rate.
  let cameraFrames = 0;
  if (video.requestVideoFrameCallback) {
    const count = () => { cameraFrames++; if (live.running) video.requestVideoFrameCallback(count); };
    video.requestVideoFrameCallback(count);
  }
  while (live.running) {
    await nextVideoFrame(video);
    if (!live.running) return;
    const w = video.videoWidth;
    const h = video.videoHeight;
    if (!w || !h || (!video.requestVideoFrameCallback && video.currentTime === lastFrameTime)) continue;
    lastFrameTime = video.currentTime;
    if (grab.width !== w || grab.height !== h) {
      grab.width = w; grab.height = h;
      overlay.width = w; overlay.height = h;
      $("l-res").textContent = `${w} × ${h}`;
    }
    gctx.drawImage(video, 0, 0, w, h);
    const data = gctx.getImageData(0, 0, w, h).data.buffer;
    let result;
    try {
      result = await liveEngine.call("liveFrame", { data, width: w, height: h, framed: live.framed }, [data]);
    } catch (err) {
      showMsg($("live-msg"), "error", err.message);
      liveStop();
      return;
    }
    if (!live.running) return;
    octx.drawImage(grab, 0, 0);
    drawDetections(octx, w, h, result.detections);
    // The tables follow at a readable pace, not every frame.
    if (result.frame && performance.now() - live.shown > 250) {
      live.shown = performance.now();
      $("l-json").textContent = result.frame;
      $("l-cli").textContent = "";
      showFrame(JSON.parse(result.frame));
    }
    windowFrames++;
    live.ms = live.ms ? live.ms * 0.9 + result.ms * 0.1 : result.ms;
    const now = performance.now();
    if (now - windowStart >= 1000) {
      const fps = (windowFrames * 1000) / (now - windowStart);
      $("l-fps").textContent = `${fps.toFixed(1)} fps`;
      $("l-fps").dataset.fps = fps.toFixed(2);
      $("l-ms").textContent = `${live.ms.toFixed(1)} ms`;
      if (cameraFrames) {
        const camera = (cameraFrames * 1000) / (now - windowStart);
        $("l-camera").textContent = `${camera.toFixed(1)} fps`;
        $("l-camera").dataset.fps = camera.toFixed(2);
      }
      windowStart = now;
      windowFrames = 0;
      cameraFrames = 0;
    }
  }
}

function drawDetections(ctx, w, h, d) {
  const stride = live.stride;
  const ids = [];
  const line = Math.max(2, w / 320);
  const big = Math.round(Math.max(13, w / 48));
  const small = Math.round(big * 0.8);
  ctx.textBaseline = "bottom";
  ctx.lineJoin = "round";
  const legacy = document.querySelector("input[name=live-style]:checked").value === "legacy";
  const label = (text, size, x, y) => {
    ctx.font = `600 ${size}px system-ui, sans-serif`;
    const tx = x - ctx.measureText(text).width / 2;
    ctx.lineWidth = 4;
    ctx.strokeStyle = "rgba(0,0,0,.8)";
    ctx.strokeText(text, tx, y);
    ctx.fillStyle = "#fff";
    ctx.fillText(text, tx, y);
  };
  for (let k = 0; k + stride <= d.length; k += stride) {
    const [id, u, v, a, b, angle, yaw, , ax, ay] = d.subarray(k, k + stride);
    // Detector coordinates put the first pixel's centre at 0; the canvas at 0.5.
    const x = u + 0.5;
    const y = v + 0.5;
    const known = id > 0;
    ctx.lineWidth = line;
    ctx.strokeStyle = known ? "#00e676" : "#ffb300";
    ctx.beginPath();
    ctx.ellipse(x, y, a, b, angle, 0, 2 * Math.PI);
    ctx.stroke();
    if (!Number.isNaN(yaw)) {
      ctx.strokeStyle = "#ff1744";
      ctx.beginPath();
      ctx.moveTo(x, y);
      ctx.lineTo(x + Math.cos(yaw) * a, y + Math.sin(yaw) * a);
      ctx.stroke();
    }
    const top = y - Math.max(a, b) - line;
    if (!Number.isNaN(ax)) {
      // On an arena: the floor place (metres) in place of the image yaw.
      label(`${ax.toFixed(3)}, ${ay.toFixed(3)} m`, small, x, top);
      label(known ? `ID ${id}` : legacy ? "WhyCon" : "unknown", big, x, top - small - 4);
    } else if (known && !Number.isNaN(yaw)) {
      label(`${Math.round((yaw * 180) / Math.PI)}°`, small, x, top);
      label(`ID ${id}`, big, x, top - small - 4);
    } else {
      label(known ? `ID ${id}` : legacy ? "WhyCon" : "unknown", big, x, top);
    }
    if (known) ids.push(id);
  }
  ids.sort((p, q) => p - q);
  $("l-ids").textContent = d.length ? `${d.length / stride} in view${ids.length ? `: ID ${ids.join(", ")}` : ""}` : "none in view";
  $("l-ids").dataset.ids = ids.join(",");
}

$("l-start").addEventListener("click", liveStart);
$("l-photo").addEventListener("change", (e) => livePhoto(e.target));
$("l-frames-clear").addEventListener("click", () => {
  for (const id of ["l-camera-file", "l-boards", "l-arena"]) $(id).value = "";
  $("l-diameter").value = "";
});
$("l-stop").addEventListener("click", liveStop);
document.addEventListener("visibilitychange", () => { if (document.hidden && live.running) liveStop(); });

// ---------- start ----------

async function start() {
  const status = $("engine-status");
  try {
    const hello = await engine.call("hello", {});
    performance.mark("whycode-engine-ready");
    status.className = "engine ready";
    $("version").textContent = `whycode ${hello.version}`;
    fillTemplates(hello.templates);
    idsUpdate();
    idsCounts();
    listPhotos();
    calList();
    syncPrintForm();
    printPreview();
  } catch (err) {
    status.className = "engine failed";
    status.textContent = `The whycode engine did not load: ${err.message}. This page needs a browser with WebAssembly and module workers (recent Chrome, Edge, Firefox or Safari).`;
  }
}

const initial = location.hash.slice(1);
showPanel(["ids", "print", "check", "calibrate", "live"].includes(initial) ? initial : "ids");
start();

if ("serviceWorker" in navigator && location.protocol !== "file:") {
  navigator.serviceWorker.register("sw.js").catch(() => {});
}

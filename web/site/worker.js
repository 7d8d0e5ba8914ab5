// The whycode engine off the page's thread: every call that can take time
// (family generation, sheet layout and self-check, photo checks, live
// frames) runs here, so the page stays responsive, and a job that runs too
// long can be ended by terminating the worker.
import init, * as wc from "./pkg/whycode_web.js";

const ready = init({ module_or_path: new URL("./pkg/whycode_web_bg.wasm", import.meta.url) });
let validation = null;
let calibration = null;

// PDF output lives in a module of its own (printpdf, with its fonts and
// colour profile, is as large as the rest of the library): fetched on the
// first PDF, so the page's first load stays small.
// The Live panel's camera, board and arena files are read by the same
// second module (their YAML and XML readers are as large).
let pdfModule = null;
function second(what, offlineHint) {
  if (!pdfModule) {
    pdfModule = import("./pkg/whycode_pdf.js").then(async (m) => {
      await m.default({ module_or_path: new URL("./pkg/whycode_pdf_bg.wasm", import.meta.url) });
      return m;
    });
    pdfModule.catch(() => { pdfModule = null; });
  }
  return pdfModule.catch((err) => {
    const offline = self.navigator && self.navigator.onLine === false;
    throw new Error(`${what} did not load (${err.message || err})${offline ? `; ${offlineHint}` : ""}`);
  });
}
const pdf = () => second("the PDF writer", "it is fetched the first time a PDF is made online, SVG and PNG work offline");
const engineFor = async (options) => (options.output.toLowerCase().endsWith(".pdf") ? pdf() : wc);
const liveEngineFor = async (options) =>
  (options.camera || options.arena || options.boards.length
    ? second("the reader of camera, board and arena files", "it is fetched the first time such a file is given online")
    : wc);
let live = null;

function files(out) {
  const list = [];
  for (let k = 0; k < out.count(); k++) list.push({ name: out.name(k), bytes: out.bytes(k) });
  const notes = out.notes();
  out.free();
  return { files: list, notes };
}

const handlers = {
  hello: () => ({ version: wc.version(), templates: JSON.parse(wc.templates()) }),
  familyTable: ({ bits, distance, limit }) => JSON.parse(wc.familyTable(bits, distance, limit)),
  familyJson: ({ bits, distance }) => wc.familyJson(bits, distance),
  counts: ({ bits, distances }) =>
    JSON.parse(wc.counts(Uint32Array.from(bits), Uint32Array.from(distances))),
  sheet: async (options) => files((await engineFor(options)).sheet(JSON.stringify(options))),
  marker: async (options) => files((await engineFor(options)).marker(JSON.stringify(options))),
  validateStart: ({ name, text }) => {
    if (validation) validation.free();
    validation = null;
    validation = new wc.Validation(name, text);
    return true;
  },
  validatePhoto: ({ name, bytes }) => validation.addPhoto(name, new Uint8Array(bytes)),
  validateReport: () => ({ json: validation.reportJson(), table: validation.reportTable() }),
  calibrateStart: ({ name, text }) => {
    if (calibration) calibration.free();
    calibration = null;
    calibration = new wc.Calibration(name, text);
    return true;
  },
  calibratePhoto: ({ name, bytes }) => calibration.addPhoto(name, new Uint8Array(bytes)),
  calibrateRemove: ({ index }) => calibration.removePhoto(index),
  calibratePreview: ({ options }) => JSON.parse(calibration.preview(JSON.stringify(options))),
  calibrateRun: ({ options, output }) => {
    const json = calibration.calibrate(JSON.stringify(options));
    return { json, table: calibration.reportTable(), camera: calibration.cameraFile(output) };
  },
  liveStart: async ({ options }) => {
    if (live) live.free();
    live = null;
    const engine = await liveEngineFor(options);
    live = new engine.Live(JSON.stringify(options));
    return engine.liveStride();
  },
  liveFrame: ({ data, width, height, framed }) => {
    const t0 = performance.now();
    const out = live.detectRgba(new Uint8Array(data), width, height);
    const ms = performance.now() - t0;
    return { detections: out, ms, buffer: data, frame: framed ? live.frameJson() : null };
  },
  // A photo has a detector of its own, so a running camera's tracks stay.
  livePhoto: async ({ options, name, bytes }) => {
    const photo = new (await liveEngineFor(options)).Live(JSON.stringify(options));
    try {
      return photo.detectPhoto(name, new Uint8Array(bytes));
    } finally {
      photo.free();
    }
  },
};

self.onmessage = async (event) => {
  const { id, op, args } = event.data;
  try {
    await ready;
    const result = await handlers[op](args);
    const transfer = [];
    if (result instanceof Uint8Array) transfer.push(result.buffer);
    if (result && result.buffer instanceof ArrayBuffer && op === "liveFrame") transfer.push(result.buffer);
    if (result && Array.isArray(result.files)) for (const f of result.files) transfer.push(f.bytes.buffer);
    self.postMessage({ id, ok: true, result }, transfer);
  } catch (err) {
    // A Rust panic surfaces as a RuntimeError ("unreachable"); the engine's
    // state is then unusable, which the page learns from `fatal`.
    const fatal = err instanceof WebAssembly.RuntimeError;
    self.postMessage({ id, ok: false, error: String(err && err.message ? err.message : err), fatal });
  }
};

// irad's image viewer (src/html/viewer.rs writes its data; docs/DESIGN.md "Looking at results"
// on why half floats and one canvas). report.html, `irad render --html` and `irad compare
// --html` embed it.
// No library: images arrive as half-float RGB in base64, are decoded when first shown into
// Float32Arrays, and drawn into a canvas with nearest-neighbour zoom, so one screen pixel shows
// one image pixel's exact value at any zoom.
//
// A viewer compares image A (a run) with image B (the reference or another run):
//   split   - A left of the slider, B right of it;
//   flip    - A or B, toggled with F (or the flip button);
//   relmse  - per-pixel relMSE of A against B, log scale 1e-4 (black) .. 10 (white);
//   signed  - (Y(A) - Y(B)) / sqrt(Y(B)^2 + 0.01), blue -1 .. black 0 .. red +1;
//   flipmap - A's HDR-FLIP map against the reference (computed by irad), 0 (black) .. 1 (white).
// Exposure (stops) and the tone curve apply to split and flip. Wheel zooms about the cursor,
// drag pans; A and B always share the view (one canvas). The readout shows both pixels' values.
// A viewer of several frames adds play/pause (space), a scrubber, steps (arrow keys) and, where
// there is a reference, the per-frame relMSE plot with the current frame marked.
"use strict";

const HALF = (() => {
  // Every half float's value, indexed by its bits.
  const table = new Float32Array(65536);
  for (let h = 0; h < 65536; h++) {
    const s = h & 0x8000 ? -1 : 1;
    const e = (h >> 10) & 0x1f;
    const m = h & 0x3ff;
    let v;
    if (e === 0) v = m * Math.pow(2, -24);
    else if (e === 31) v = m ? NaN : Infinity;
    else v = (1 + m / 1024) * Math.pow(2, e - 15);
    table[h] = s * v;
  }
  return table;
})();

// base64 half-float RGB, `width` x `height`, rows top to bottom, into a Float32Array.
function decodeImage(b64, width, height) {
  const text = atob(b64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i++) bytes[i] = text.charCodeAt(i);
  const halves = new Uint16Array(bytes.buffer, 0, 3 * width * height);
  const out = new Float32Array(halves.length);
  for (let i = 0; i < halves.length; i++) out[i] = HALF[halves[i]];
  return { width, height, rgb: out };
}

// base64 bytes (a FLIP map: round(255 v) a pixel) into a Float32Array of v.
function decodeBytes(b64) {
  const text = atob(b64);
  const out = new Float32Array(text.length);
  for (let i = 0; i < text.length; i++) out[i] = text.charCodeAt(i) / 255;
  return out;
}

const TONE = {
  srgb: (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055),
  gamma22: (v) => Math.pow(Math.max(v, 0), 1 / 2.2),
  linear: (v) => v,
  // Narkowicz's ACES fit, then sRGB.
  aces: (v) => TONE.srgb((v * (2.51 * v + 0.03)) / (v * (2.43 * v + 0.59) + 0.14)),
};

function luminance(r, g, b) {
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

// The heat ramp of the reports' error maps (src/image/preview.rs): black, dark red, red,
// orange, yellow, white at equal steps of log10(e) over [1e-4, 10].
const HEAT = [
  [0, 0, 0], [0.35, 0, 0.05], [0.8, 0.1, 0.05], [1, 0.5, 0], [1, 0.9, 0.1], [1, 1, 1],
];
function heat(t) {
  const s = Math.min(Math.max(t, 0), 1) * (HEAT.length - 1);
  const i = Math.min(Math.floor(s), HEAT.length - 2);
  const u = s - i;
  return HEAT[i].map((c, k) => 255 * (c + u * (HEAT[i + 1][k] - c)));
}
function heatOfError(e) {
  return heat(e > 0 ? (Math.log10(e) + 4) / 5 : 0);
}
// Blue, black at 0.5, red (src/image/error_maps.rs's diverging ramp).
function diverging(t) {
  const s = 2 * Math.min(Math.max(t, 0), 1) - 1;
  return s < 0 ? [64 * -s, 140 * -s, 255 * -s] : [255 * s, 51 * s, 26 * s];
}

const MODES = [
  ["split", "split"],
  ["flip", "flip"],
  ["relmse", "relMSE"],
  ["signed", "signed error"],
  ["flipmap", "FLIP"],
];

class Viewer {
  // `data`: { names, reference (a name or null), fps, factor, frames: [{ number, relmse,
  // images: [{ width, height, rgb, flip? }, in the order of names] }] } as src/html/viewer.rs
  // writes it.
  constructor(root, data, options = {}) {
    this.root = root;
    this.data = data;
    this.names = data.names;
    this.index = new Map(this.names.map((n, i) => [n, i]));
    this.reference = data.reference;
    this.frame = 0; // index into data.frames
    const other = this.names.find((n) => n !== this.reference) || this.names[0];
    this.a = options.a || other;
    this.b = options.b || this.reference || this.names[this.names.length > 1 ? 1 : 0];
    this.mode = "split";
    this.showB = false; // flip mode: which one is shown
    this.exposure = 0;
    this.tone = "srgb";
    this.split = 0.5; // the slider's place, a fraction of the canvas width
    this.playing = null;
    this.canvas = root.querySelector("canvas.view");
    this.bar = root.querySelector("canvas.bar");
    this.readout = root.querySelector(".readout");
    this.note = root.querySelector(".note");
    this.hasFlip = data.frames.some((f) => f.images.some((im) => im.flip));
    this.cursor = null; // the last canvas point under the pointer, for the readout
    this.fit();
    this.bind();
    if (data.frames.length > 1) this.bindSequence();
    this.draw();
  }

  entry(name) {
    return this.data.frames[this.frame].images[this.index.get(name)];
  }

  // The decoded image `name` of the current frame.
  image(name) {
    const e = this.entry(name);
    if (!e.decoded) e.decoded = decodeImage(e.rgb, e.width, e.height);
    return e.decoded;
  }

  // A's FLIP map against the reference, or null where there is none (B is not the reference,
  // or irad computed none).
  flipMap() {
    const e = this.entry(this.a);
    if (this.b !== this.reference || !e.flip) return null;
    if (!e.flipDecoded) e.flipDecoded = decodeBytes(e.flip);
    return e.flipDecoded;
  }

  // The whole image in the canvas, at an integer zoom where it fits.
  fit() {
    const im = this.image(this.a);
    const fits = Math.min(this.canvas.width / im.width, this.canvas.height / im.height);
    // An integer zoom where the image fits at 1:1 or more, else the fraction that fits.
    const scale = fits >= 1 ? Math.floor(fits) : fits;
    this.scale = scale;
    this.ox = (this.canvas.width - im.width * scale) / 2;
    this.oy = (this.canvas.height - im.height * scale) / 2;
  }

  // Canvas pixel -> image pixel (integer), or null outside the image.
  pixelAt(cx, cy) {
    const im = this.image(this.a);
    const x = Math.floor((cx - this.ox) / this.scale);
    const y = Math.floor((cy - this.oy) / this.scale);
    return x >= 0 && y >= 0 && x < im.width && y < im.height ? [x, y] : null;
  }

  value(name, x, y) {
    const im = this.image(name);
    if (x >= im.width || y >= im.height) return [NaN, NaN, NaN];
    const i = 3 * (y * im.width + x);
    return [im.rgb[i], im.rgb[i + 1], im.rgb[i + 2]];
  }

  colour(cx, x, y, map) {
    const A = this.value(this.a, x, y);
    const B = this.value(this.b, x, y);
    if (this.mode === "flipmap") {
      return map ? heat(map[y * this.image(this.a).width + x]) : [64, 64, 64];
    }
    if (this.mode === "relmse") {
      if (!A.every(Number.isFinite) || !B.every(Number.isFinite)) return [255, 0, 255];
      let e = 0;
      for (let c = 0; c < 3; c++) e += ((A[c] - B[c]) ** 2 / (B[c] * B[c] + 0.01)) / 3;
      return heatOfError(e);
    }
    if (this.mode === "signed") {
      if (!A.every(Number.isFinite) || !B.every(Number.isFinite)) return [255, 0, 255];
      const ya = luminance(...A);
      const yb = luminance(...B);
      return diverging(0.5 + 0.5 * Math.max(-1, Math.min(1, (ya - yb) / Math.sqrt(yb * yb + 0.01))));
    }
    const useB = this.mode === "flip" ? this.showB : cx >= this.split * this.canvas.width;
    const v = useB ? B : A;
    const k = Math.pow(2, this.exposure);
    const tone = TONE[this.tone];
    // +Inf (past the half floats' range) is white, NaN black.
    return v.map((c) => (Number.isNaN(c) ? 0 : c === Infinity ? 255 : 255 * Math.min(Math.max(tone(c * k), 0), 1)));
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    const { width, height } = this.canvas;
    const out = ctx.createImageData(width, height);
    const map = this.mode === "flipmap" ? this.flipMap() : null;
    for (let cy = 0; cy < height; cy++) {
      for (let cx = 0; cx < width; cx++) {
        const p = this.pixelAt(cx + 0.5, cy + 0.5);
        const o = 4 * (cy * width + cx);
        const rgb = p ? this.colour(cx, p[0], p[1], map) : [32, 32, 32];
        out.data[o] = rgb[0];
        out.data[o + 1] = rgb[1];
        out.data[o + 2] = rgb[2];
        out.data[o + 3] = 255;
      }
    }
    ctx.putImageData(out, 0, 0);
    if (this.mode === "split") {
      const x = Math.round(this.split * width) + 0.5;
      ctx.strokeStyle = "#fff";
      ctx.beginPath();
      ctx.moveTo(x, 0);
      ctx.lineTo(x, height);
      ctx.stroke();
    }
    this.drawBar();
    let note = "";
    if (this.mode === "flipmap" && !map) {
      if (!this.reference) note = "no FLIP maps: there is no reference";
      else if (this.b !== this.reference) note = `FLIP maps are of each image against ${this.reference}: choose it as B`;
      else if (this.a === this.reference) note = "A is the reference: choose another image as A";
      else note = "no FLIP map for A: irad computes none where A or the reference has NaN or Inf values";
    }
    this.note.textContent = note;
    this.root.dataset.mode = this.mode;
    this.root.dataset.shown = this.mode === "flip" ? (this.showB ? this.b : this.a) : "";
    this.root.dataset.frame = this.data.frames[this.frame].number;
    if (this.plot) this.drawPlot();
    if (this.cursor) this.showReadout(...this.cursor);
  }

  drawBar() {
    const ctx = this.bar.getContext("2d");
    const { width, height } = this.bar;
    ctx.clearRect(0, 0, width, height);
    if (this.mode !== "relmse" && this.mode !== "signed" && this.mode !== "flipmap") return;
    for (let x = 0; x < width; x++) {
      const t = x / (width - 1);
      const rgb = this.mode === "signed" ? diverging(t) : heat(t);
      ctx.fillStyle = `rgb(${rgb[0]},${rgb[1]},${rgb[2]})`;
      ctx.fillRect(x, 0, 1, height - 14);
    }
    ctx.fillStyle = "#222";
    ctx.font = "11px sans-serif";
    const labels = {
      relmse: ["1e-4", "1e-3", "0.01", "0.1", "1", "10"],
      signed: ["-1", "-0.5", "0", "0.5", "1"],
      flipmap: ["0", "0.25", "0.5", "0.75", "1"],
    }[this.mode];
    labels.forEach((l, i) => {
      const x = (i / (labels.length - 1)) * (width - 1);
      ctx.textAlign = i === 0 ? "left" : i === labels.length - 1 ? "right" : "center";
      ctx.fillText(l, x, height - 2);
    });
  }

  showReadout(cx, cy) {
    // The pixel drawn at this canvas pixel (draw samples its centre).
    const p = this.pixelAt(Math.floor(cx) + 0.5, Math.floor(cy) + 0.5);
    if (!p) {
      this.readout.textContent = "";
      return;
    }
    const fmt = (v) => v.map((c) => c.toPrecision(5)).join(", ");
    // Box-filtered images: a pixel here is the mean of f x f of the EXR's.
    const f = this.data.factor || 1;
    const [w, h] = this.data.size || [Infinity, Infinity];
    const x1 = Math.min(p[0] * f + f, w) - 1;
    const y1 = Math.min(p[1] * f + f, h) - 1;
    const where = f > 1
      ? `(${p[0] * f}..${x1}, ${p[1] * f}..${y1}) mean of ${x1 - p[0] * f + 1}x${y1 - p[1] * f + 1}`
      : `(${p[0]}, ${p[1]})`;
    const A = this.value(this.a, p[0], p[1]);
    const B = this.value(this.b, p[0], p[1]);
    this.readout.dataset.x = p[0];
    this.readout.dataset.y = p[1];
    this.readout.dataset.a = A.join(",");
    this.readout.dataset.b = B.join(",");
    const map = this.flipMap();
    const flip = map ? `  FLIP ${map[p[1] * this.image(this.a).width + p[0]].toFixed(3)}` : "";
    this.readout.textContent = `${where}  ${this.a}: ${fmt(A)}  |  ${this.b}: ${fmt(B)}${flip}`;
  }

  // Zoom by `factor` about canvas point (cx, cy), keeping the image pixel under it in place.
  zoom(factor, cx, cy) {
    const scale = Math.min(Math.max(this.scale * factor, 0.25), 256);
    this.ox = cx - ((cx - this.ox) * scale) / this.scale;
    this.oy = cy - ((cy - this.oy) * scale) / this.scale;
    this.scale = scale;
    this.draw();
  }

  setA(name) {
    this.a = name;
    this.root.querySelector("select.a").value = name;
    this.draw();
  }

  bind() {
    const c = this.canvas;
    // Client point -> canvas pixel, inside the canvas's border.
    const local = (e) => {
      const r = c.getBoundingClientRect();
      return [
        ((e.clientX - r.left - c.clientLeft) * c.width) / c.clientWidth,
        ((e.clientY - r.top - c.clientTop) * c.height) / c.clientHeight,
      ];
    };
    c.addEventListener("wheel", (e) => {
      if (e.deltaY === 0) return;
      e.preventDefault();
      const [cx, cy] = local(e);
      this.cursor = [cx, cy];
      this.zoom(e.deltaY < 0 ? 2 : 0.5, cx, cy);
    });
    let drag = null;
    c.addEventListener("pointerdown", (e) => {
      drag = local(e);
      c.setPointerCapture(e.pointerId);
    });
    c.addEventListener("pointerup", () => (drag = null));
    c.addEventListener("pointerleave", () => {
      this.cursor = null;
      this.readout.textContent = "";
    });
    c.addEventListener("pointercancel", () => (drag = null));
    c.style.touchAction = "none";
    c.addEventListener("pointermove", (e) => {
      const [cx, cy] = local(e);
      this.cursor = [cx, cy];
      if (drag) {
        if (this.mode === "split" && e.shiftKey) {
          this.split = Math.min(Math.max(cx / c.width, 0), 1);
          this.root.querySelector("input.split").value = Math.round(100 * this.split);
        } else {
          this.ox += cx - drag[0];
          this.oy += cy - drag[1];
        }
        drag = [cx, cy];
        this.draw();
      }
      this.showReadout(cx, cy);
    });
    const q = (sel) => this.root.querySelector(sel);
    const sel = (s, names, value, set) => {
      s.replaceChildren(...names.map(([v, label]) => new Option(label, v, false, v === value)));
      s.addEventListener("change", () => {
        set(s.value);
        this.draw();
      });
    };
    const named = this.names.map((n) => [n, n]);
    sel(q("select.a"), named, this.a, (v) => (this.a = v));
    sel(q("select.b"), named, this.b, (v) => (this.b = v));
    // One image: nothing to compare it with.
    const modes = MODES.filter(([m]) => (m === "split" || this.names.length > 1) && (m !== "flipmap" || this.hasFlip));
    sel(q("select.mode"), modes, this.mode, (v) => (this.mode = v));
    q("select.tone").addEventListener("change", (e) => {
      this.tone = e.target.value;
      this.draw();
    });
    const exposure = q("input.exposure");
    exposure.addEventListener("input", () => {
      this.exposure = Number(exposure.value);
      q(".exposure-value").textContent = `${this.exposure >= 0 ? "+" : ""}${this.exposure.toFixed(1)} stops`;
      this.draw();
    });
    const split = q("input.split");
    split.addEventListener("input", () => {
      this.split = Number(split.value) / 100;
      this.draw();
    });
    q("button.flip").addEventListener("click", () => this.flip());
    q("button.fit").addEventListener("click", () => {
      this.fit();
      this.draw();
    });
    this.root.tabIndex = 0;
    const sequence = this.data.frames.length > 1;
    this.root.addEventListener("keydown", (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey) return;
      if (e.target.tagName === "SELECT" || e.target.tagName === "INPUT") return;
      if (e.key === "f" || e.key === "F") this.flip();
      else if (e.key === "e") exposure.stepUp(), exposure.dispatchEvent(new Event("input"));
      else if (e.key === "E") exposure.stepDown(), exposure.dispatchEvent(new Event("input"));
      else if (sequence && e.key === " ") this.togglePlay();
      else if (sequence && e.key === "ArrowRight") this.step(1);
      else if (sequence && e.key === "ArrowLeft") this.step(-1);
      else return;
      e.preventDefault();
    });
  }

  // The sequence's controls above the image: play/pause, steps, the scrubber, the frame's
  // number, then the per-frame error plot (where there is a reference).
  bindSequence() {
    const n = this.data.frames.length;
    // Above the image, so that the controls stay in place while it zooms.
    const div = document.createElement("div");
    div.className = "sequence";
    div.innerHTML =
      '<button class="play">play</button> <button class="prev">&#9664;</button>' +
      ` <input class="scrubber" type="range" min="0" max="${n - 1}" value="0" step="1">` +
      ' <button class="next">&#9654;</button> <span class="frame-label"></span>';
    this.canvas.before(div);
    const q = (sel) => div.querySelector(sel);
    this.scrubber = q("input.scrubber");
    this.frameLabel = q(".frame-label");
    this.playButton = q("button.play");
    this.scrubber.addEventListener("input", () => this.setFrame(Number(this.scrubber.value)));
    q("button.prev").addEventListener("click", () => this.step(-1));
    q("button.next").addEventListener("click", () => this.step(1));
    this.playButton.addEventListener("click", () => this.togglePlay());
    this.plot = null;
    if (this.data.frames.some((f) => f.relmse !== null)) {
      this.plot = document.createElement("canvas");
      this.plot.className = "plot";
      this.plot.width = this.canvas.width;
      this.plot.height = 120;
      div.after(this.plot);
      this.plot.addEventListener("click", (e) => {
        const r = this.plot.getBoundingClientRect();
        const x = ((e.clientX - r.left - this.plot.clientLeft) * this.plot.width) / this.plot.clientWidth;
        this.setFrame(Math.round(((x - 40) / (this.plot.width - 50)) * (n - 1)));
      });
    }
    this.root.dataset.playing = "false";
    this.frameLabel.textContent = `frame ${this.data.frames[0].number} (1 of ${n})`;
  }

  setFrame(i) {
    const n = this.data.frames.length;
    this.frame = Math.min(Math.max(i, 0), n - 1);
    if (this.scrubber) this.scrubber.value = this.frame;
    if (this.frameLabel) this.frameLabel.textContent = `frame ${this.data.frames[this.frame].number} (${this.frame + 1} of ${n})`;
    this.draw();
  }

  step(d) {
    const n = this.data.frames.length;
    this.setFrame((this.frame + d + n) % n);
  }

  togglePlay() {
    if (this.playing) {
      clearInterval(this.playing);
      this.playing = null;
    } else {
      this.playing = setInterval(() => this.step(1), 1000 / this.data.fps);
    }
    this.playButton.textContent = this.playing ? "pause" : "play";
    this.root.dataset.playing = this.playing ? "true" : "false";
  }

  // log10 relMSE per frame, the current frame marked by a vertical line and a dot; a frame
  // equal to the reference (relMSE 0) sits on the axis's floor.
  drawPlot() {
    const ctx = this.plot.getContext("2d");
    const { width, height } = this.plot;
    ctx.clearRect(0, 0, width, height);
    const frames = this.data.frames;
    const n = frames.length;
    const positive = frames.filter((f) => f.relmse > 0).map((f) => Math.log10(f.relmse));
    let lo = positive.length ? Math.floor(Math.min(...positive)) : -1;
    let hi = positive.length ? Math.ceil(Math.max(...positive)) : 0;
    if (hi === lo) hi = lo + 1;
    const logs = frames.map((f) => (f.relmse === null ? null : f.relmse > 0 ? Math.log10(f.relmse) : lo));
    const X = (i) => 40 + (n > 1 ? (i / (n - 1)) * (width - 50) : 0);
    const Y = (v) => 8 + (1 - (v - lo) / (hi - lo)) * (height - 26);
    ctx.strokeStyle = "#ccc";
    ctx.fillStyle = "#444";
    ctx.font = "10px sans-serif";
    ctx.textAlign = "right";
    for (let e = lo; e <= hi; e++) {
      ctx.beginPath();
      ctx.moveTo(40, Y(e) + 0.5);
      ctx.lineTo(width - 10, Y(e) + 0.5);
      ctx.stroke();
      ctx.fillText(`1e${e}`, 36, Y(e) + 3);
    }
    ctx.textAlign = "center";
    const caption = positive.length ? "relMSE per frame" : "relMSE per frame: 0, every frame equal to the reference";
    ctx.fillText(`${caption} (frames ${frames[0].number}..${frames[n - 1].number})`, width / 2, height - 4);
    ctx.strokeStyle = "#2060c0";
    ctx.beginPath();
    let started = false;
    logs.forEach((v, i) => {
      if (v === null) return (started = false);
      if (started) ctx.lineTo(X(i), Y(v));
      else ctx.moveTo(X(i), Y(v)), (started = true);
    });
    ctx.stroke();
    const x = Math.round(X(this.frame)) + 0.5;
    ctx.strokeStyle = "#d03020";
    ctx.beginPath();
    ctx.moveTo(x, 4);
    ctx.lineTo(x, height - 16);
    ctx.stroke();
    if (logs[this.frame] !== null) {
      ctx.fillStyle = "#d03020";
      ctx.beginPath();
      ctx.arc(x, Y(logs[this.frame]), 3.5, 0, 2 * Math.PI);
      ctx.fill();
    }
  }

  flip() {
    if (this.names.length < 2) return;
    if (this.mode !== "flip") {
      this.mode = "flip";
      this.root.querySelector("select.mode").value = "flip";
      this.showB = false;
    }
    this.showB = !this.showB;
    this.draw();
  }
}

window.IradViewer = { Viewer, decodeImage, decodeBytes, HALF };

// Strip charts of the viewer on 2-D canvases: one line per series over the session's time,
// a cursor at the frame shown. Samples are stored by record index, so scrubbing back and forth
// never loses what was already simulated.

const PALETTE = ['#1f77b4', '#d62728', '#2ca02c', '#ff7f0e', '#9467bd', '#8c564b', '#e377c2',
  '#7f7f7f', '#bcbd22', '#17becf'];

export class StripChart {
  // canvas: the element; names: series labels; unit: label of the y axis.
  constructor(canvas, title, names, unit, records) {
    this.canvas = canvas;
    this.title = title;
    this.names = names;
    this.unit = unit;
    this.time = new Float64Array(records).fill(NaN);
    this.values = names.map(() => new Float32Array(records).fill(NaN));
    this.cursor = -1;
    this.dirty = true;
  }

  set(record, time, values) {
    if (record < 0 || record >= this.time.length) return;
    this.time[record] = time;
    for (let s = 0; s < this.values.length; s++) this.values[s][record] = values[s];
    this.cursor = record;
    this.dirty = true;
  }

  clear() {
    this.time.fill(NaN);
    for (const v of this.values) v.fill(NaN);
    this.cursor = -1;
    this.dirty = true;
  }

  draw(duration) {
    if (!this.dirty) return;
    this.dirty = false;
    const c = this.canvas;
    const dpr = window.devicePixelRatio || 1;
    const w = c.clientWidth, h = c.clientHeight;
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    let lo = Infinity, hi = -Infinity;
    for (const v of this.values) for (const x of v) if (!Number.isNaN(x)) { lo = Math.min(lo, x); hi = Math.max(hi, x); }
    if (!(hi > lo)) { lo = (Number.isFinite(lo) ? lo : 0) - 1; hi = lo + 2; }
    const pad = 0.05 * (hi - lo);
    lo -= pad; hi += pad;
    g.fillStyle = '#222';
    g.font = '11px sans-serif';
    g.fillText(`${this.title} [${this.unit}]`, 2, 11);
    // Legend (at most 10 entries) with the values at the cursor: above the plot area, in as
    // many lines as it needs, so that it never hides a curve.
    g.font = '10px sans-serif';
    const lineHeight = 12;
    let lx = 2, ly = 11 + lineHeight;
    for (let s = 0; s < Math.min(this.names.length, 10); s++) {
      const value = this.cursor >= 0 ? this.values[s][this.cursor] : NaN;
      const label = `${this.names[s]} ${Number.isNaN(value) ? '' : fmt(value)}`;
      const width = g.measureText(label).width;
      if (lx > 2 && lx + width > w - 2) { lx = 2; ly += lineHeight; }
      g.fillStyle = PALETTE[s % PALETTE.length];
      g.fillText(label, lx, ly);
      lx += width + 10;
    }
    const left = 46, right = 6, top = ly + 6, bottom = 16;
    const px = (t) => left + (w - left - right) * (t / Math.max(duration, 1e-9));
    const py = (v) => top + (h - top - bottom) * (1 - (v - lo) / (hi - lo));
    g.fillStyle = '#666';
    g.fillText(fmt(hi), 2, top + 8);
    g.fillText(fmt(lo), 2, h - bottom);
    g.fillText(`${duration.toFixed(1)} s`, w - right - 34, h - 3);
    g.strokeStyle = '#ccc';
    g.strokeRect(left, top, w - left - right, h - top - bottom);
    for (let s = 0; s < this.values.length; s++) {
      const v = this.values[s];
      g.strokeStyle = PALETTE[s % PALETTE.length];
      g.lineWidth = 1.2;
      g.beginPath();
      let pen = false;
      for (let i = 0; i < v.length; i++) {
        if (Number.isNaN(v[i])) continue;  // a record not shown (skipped at speed): bridge it
        const x = px(this.time[i]), y = py(v[i]);
        if (pen) g.lineTo(x, y); else g.moveTo(x, y);
        pen = true;
      }
      g.stroke();
    }
    if (this.cursor >= 0 && !Number.isNaN(this.time[this.cursor])) {
      g.strokeStyle = '#000';
      g.lineWidth = 1;
      g.beginPath();
      g.moveTo(px(this.time[this.cursor]), top);
      g.lineTo(px(this.time[this.cursor]), h - bottom);
      g.stroke();
    }
  }
}

function fmt(v) {
  const a = Math.abs(v);
  if (a >= 1000 || (a > 0 && a < 0.01)) return v.toExponential(1);
  return v.toFixed(a >= 100 ? 0 : 2);
}

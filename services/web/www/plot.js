// The live plot: up to maxPlotted signals on a <canvas>, one lane each (its own y range,
// scaled to what the window shows), a shared scrolling time axis (the last 30/60/120 s, the
// right edge is "now" on the server's clock) and a legend with each signal's colour and
// current value. Values are held as steps until the next value (vcu-web sends only changes);
// null values (nothing shown) and Stale/NotConnected stretches are gaps.
//
// Drawn at most 5 times a second and only while the page is visible.

import { byId, clear, el, formatNumber, setText } from './dom.js';

export const PLOT_COLOURS = ['#4fc3f7', '#ffb74d', '#81c784', '#f06292'];
const MAX_POINTS = 4000;  // per signal: 120 s at 20 updates a second, with room

export class LivePlot {
  constructor(canvas, catalog) {
    this.canvas = canvas;
    this.catalog = catalog;
    this.windowS = 60;
    this.keys = [];                 // plotted keys, in lane order
    this.series = new Map();        // key -> {t: [], v: [], text}
    this.serverOffsetMs = 0;        // server t - Date.now() at the last event
    this.dirty = true;
    const select = byId('plot-window');
    select.addEventListener('change', () => {
      this.windowS = Number(select.value) || 60;
      this.dirty = true;
    });
    window.addEventListener('resize', () => { this.dirty = true; });
    setInterval(() => this.draw(), 200);
  }

  setKeys(keys) {
    this.keys = keys.slice();
    for (const key of [...this.series.keys()]) {
      if (!this.keys.includes(key)) this.series.delete(key);
    }
    for (const key of this.keys) {
      if (!this.series.has(key)) this.series.set(key, { t: [], v: [], text: '', status: '' });
    }
    this.renderLegend();
    this.dirty = true;
  }

  push(update) {
    if (typeof update.t !== 'number') return;
    this.serverOffsetMs = update.t - Date.now();
    const byKey = new Map((Array.isArray(update.signals) ? update.signals : []).map((s) => [s.key, s]));
    for (const key of this.keys) {
      const signal = byKey.get(key);
      const series = this.series.get(key);
      if (!signal || !series) continue;
      const usable = typeof signal.value === 'number' && isFinite(signal.value) && signal.status === 'Ready';
      series.t.push(update.t);
      series.v.push(usable ? signal.value : null);
      if (series.t.length > MAX_POINTS) {
        series.t.splice(0, series.t.length - MAX_POINTS);
        series.v.splice(0, series.v.length - MAX_POINTS);
      }
      series.text = signal.value === null ? '—' : (signal.text || formatNumber(signal.value));
      series.status = signal.status || '';
    }
    this.updateLegendValues();
    this.dirty = true;
  }

  renderLegend() {
    const legend = byId('plot-legend');
    clear(legend);
    this.keys.forEach((key, i) => {
      const info = this.catalog.get(key) || {};
      const item = el('li', { 'data-key': key, title: key });
      const swatch = el('span', { class: 'swatch' });
      swatch.style.backgroundColor = PLOT_COLOURS[i % PLOT_COLOURS.length];  // CSSOM, allowed by the CSP
      item.appendChild(swatch);
      item.appendChild(el('span', { class: 'name' }, info.signal || key));
      item.appendChild(el('span', { class: 'value' }, ''));
      legend.appendChild(item);
    });
    if (!this.keys.length) legend.appendChild(el('li', { class: 'dim' }, 'Tick "plot" on up to 4 picked signals.'));
    this.updateLegendValues();
  }

  updateLegendValues() {
    const legend = byId('plot-legend');
    for (const item of legend.children) {
      const key = item.getAttribute('data-key');
      const series = key && this.series.get(key);
      const value = item.querySelector('.value');
      if (series && value) {
        setText(value, series.text);
        item.setAttribute('data-status', series.status || 'NotConnected');
      }
    }
  }

  resize() {
    const ratio = window.devicePixelRatio || 1;
    const width = Math.max(100, Math.floor(this.canvas.clientWidth * ratio));
    const height = Math.max(60, Math.floor(this.canvas.clientHeight * ratio));
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
    }
    return ratio;
  }

  draw() {
    if (document.hidden || !this.canvas.isConnected || this.canvas.clientWidth === 0) return;
    if (!this.dirty && !this.keys.length) return;
    this.dirty = false;
    const ratio = this.resize();
    const ctx = this.canvas.getContext('2d');
    const width = this.canvas.width;
    const height = this.canvas.height;
    const font = 11 * ratio;
    const left = 64 * ratio;
    const right = 8 * ratio;
    const top = 6 * ratio;
    const bottom = 18 * ratio;
    ctx.fillStyle = '#0d1116';
    ctx.fillRect(0, 0, width, height);
    ctx.font = `${font}px sans-serif`;
    ctx.textBaseline = 'middle';

    const nowMs = Date.now() + this.serverOffsetMs;
    const windowMs = this.windowS * 1000;
    const t0 = nowMs - windowMs;
    const plotWidth = width - left - right;
    const x = (t) => left + ((t - t0) / windowMs) * plotWidth;

    // time grid: a line every 10 s (every 20 s for 120 s)
    const step = this.windowS > 60 ? 20 : 10;
    ctx.strokeStyle = '#222b35';
    ctx.fillStyle = '#8d9aa6';
    ctx.lineWidth = 1;
    ctx.textAlign = 'center';
    for (let s = 0; s <= this.windowS; s += step) {
      const xs = x(nowMs - s * 1000);
      ctx.beginPath();
      ctx.moveTo(xs, top);
      ctx.lineTo(xs, height - bottom);
      ctx.stroke();
      ctx.fillText(s === 0 ? 'now' : `-${s} s`, Math.min(xs, width - right - 12 * ratio), height - bottom / 2);
    }

    if (!this.keys.length) return;
    const laneHeight = (height - top - bottom) / this.keys.length;
    this.keys.forEach((key, lane) => {
      const series = this.series.get(key);
      const y0 = top + lane * laneHeight;
      const colour = PLOT_COLOURS[lane % PLOT_COLOURS.length];
      ctx.strokeStyle = '#222b35';
      ctx.beginPath();
      ctx.moveTo(left, y0 + laneHeight);
      ctx.lineTo(width - right, y0 + laneHeight);
      ctx.stroke();
      if (!series) return;
      // the range of what the window shows (the value before the window included: it is held)
      let first = 0;
      while (first + 1 < series.t.length && series.t[first + 1] < t0) first += 1;
      let lo = Infinity;
      let hi = -Infinity;
      for (let i = first; i < series.v.length; ++i) {
        const v = series.v[i];
        if (v === null) continue;
        lo = Math.min(lo, v);
        hi = Math.max(hi, v);
      }
      ctx.textAlign = 'right';
      ctx.fillStyle = colour;
      if (lo === Infinity) {
        ctx.fillText('no value', left - 4 * ratio, y0 + laneHeight / 2);
        return;
      }
      if (hi - lo < 1e-9) {
        const pad = Math.abs(hi) > 1 ? Math.abs(hi) * 0.1 : 1;
        lo -= pad;
        hi += pad;
      } else {
        const pad = (hi - lo) * 0.08;
        lo -= pad;
        hi += pad;
      }
      const inner = laneHeight - 8 * ratio;
      const y = (v) => y0 + 4 * ratio + inner - ((v - lo) / (hi - lo)) * inner;
      ctx.fillText(formatNumber(Number(hi.toPrecision(4))), left - 4 * ratio, y0 + 8 * ratio);
      ctx.fillText(formatNumber(Number(lo.toPrecision(4))), left - 4 * ratio, y0 + laneHeight - 8 * ratio);

      ctx.save();
      ctx.beginPath();
      ctx.rect(left, y0, plotWidth, laneHeight);
      ctx.clip();
      ctx.strokeStyle = colour;
      ctx.lineWidth = 1.5 * ratio;
      ctx.beginPath();
      let penDown = false;
      for (let i = first; i < series.t.length; ++i) {
        const v = series.v[i];
        const xs = x(Math.max(series.t[i], t0));
        const xe = i + 1 < series.t.length ? x(series.t[i + 1]) : x(nowMs);
        if (v === null) {
          penDown = false;
          continue;
        }
        const ys = y(v);
        if (penDown) ctx.lineTo(xs, ys);
        else ctx.moveTo(xs, ys);
        ctx.lineTo(xe, ys);
        penDown = true;
      }
      ctx.stroke();
      ctx.restore();
    });
    // keep scrolling
    this.dirty = true;
  }
}

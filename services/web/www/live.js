// The live view of one `update` event (docs/design/web.md): the header (FSM state and how
// long, or, while vcu-fsm is silent, the last state marked stale with how long vcu-fsm has
// been silent; SOC, health and each service, a silent one with how long), the active faults
// (DM1 DTCs and silent services included: vcu-web lists them with their source) and the
// picked-signals table. Durations and ages keep counting
// between events (vcu-web sends an event only when something changed).

import { byId, clear, el, formatAge, formatDuration, formatNumber, setAttr, setText, statusLabel } from './dom.js';

export class LiveView {
  /// picks: the Picks of app.js (keys, plotted set, toggles)
  constructor(catalog, picks) {
    this.catalog = catalog;
    this.picks = picks;
    this.stateSince = null;       // {seconds, receivedAt}
    this.stateNote = '';          // vcu-fsm silent: why the state shown is not the current one
    this.writerSilent = null;     // {seconds, receivedAt}: how long vcu-fsm has been silent
    this.signalAges = new Map();  // key -> {ageMs, receivedAt}
    this.faultKey = '';
    this.rows = new Map();        // key -> row cells
    this.faultSince = [];         // per listed fault: {seconds, receivedAt} or null
    setInterval(() => this.tick(), 500);
  }

  render(update) {
    const now = performance.now();
    const header = update.header || {};
    setText(byId('fsm-state'), header.state ?? '?');
    setAttr(byId('fsm-state'), 'data-state-index', header.stateIndex ?? '');
    const stale = header.stateStale === true;
    setAttr(byId('fsm-state'), 'data-stale', stale ? 'true' : 'false');
    setAttr(byId('fsm-state'), 'title', stale ? header.stateNote || 'not current' : '');
    this.stateNote = stale ? header.stateNote || 'vcu-fsm silent' : '';
    this.writerSilent = stale ? sinceSeconds(update.t, header.stateWriterSilentSinceUnixMs, undefined, now) : null;
    this.stateSince = sinceSeconds(update.t, header.stateSinceUnixMs, header.stateSinceS, now);
    const soc = header.soc || {};
    setText(byId('soc'), soc.text || (soc.status === 'Ready' ? '?' : statusLabel(soc.status ?? 'NotConnected')));
    setAttr(byId('soc'), 'data-status', soc.status ?? 'NotConnected');
    setText(byId('health'), statusLabel(header.health));
    setAttr(byId('health'), 'data-status', header.health ?? 'NotConnected');
    this.renderServices(Array.isArray(header.services) ? header.services : []);
    this.renderFaults(Array.isArray(update.faults) ? update.faults : [], update.t, now);
    for (const signal of Array.isArray(update.signals) ? update.signals : []) {
      this.renderSignal(signal, now);
    }
    this.tick();
  }

  renderServices(services) {
    const box = byId('services');
    if (box.children.length !== services.length) {
      clear(box);
      for (let i = 0; i < services.length; ++i) box.appendChild(el('span', { class: 'chip status' }));
    }
    services.forEach((service, i) => {
      const chip = box.children[i];
      setText(chip, String(service.name ?? '').replace(/^vcu-/, ''));
      setAttr(chip, 'data-status', service.status ?? 'NotConnected');
      setAttr(chip, 'data-liveness', service.liveness ?? '');
      const restarts = service.restarts ? `, restarted ${service.restarts} times` : '';
      setAttr(chip, 'title', `${service.name}: ${service.text || statusLabel(service.status)}${restarts}`);
    });
  }

  renderFaults(faults, t, now) {
    this.faultSince = faults.map((f) => sinceSeconds(t, f.sinceUnixMs, f.sinceS, now));
    const key = JSON.stringify(faults.map((f) => [f.name, f.source, f.severity, f.text]));
    const list = byId('faults');
    setText(byId('fault-count'), faults.length ? `(${faults.length})` : '');
    if (key === this.faultKey) return;  // only the "since" times moved: tick() shows them
    this.faultKey = key;
    clear(list);
    if (!faults.length) {
      list.appendChild(el('li', { class: 'dim none' }, 'none'));
      return;
    }
    for (const fault of faults) {
      const item = el('li', { class: 'fault', 'data-severity': fault.severity ?? '', 'data-name': fault.name ?? '' });
      item.appendChild(el('span', { class: 'severity' }, fault.severity ?? ''));
      item.appendChild(el('span', { class: 'name' }, fault.name ?? ''));
      item.appendChild(el('span', { class: 'source dim' }, fault.source ?? ''));
      item.appendChild(el('span', { class: 'since dim' }));
      if (fault.text) item.appendChild(el('div', { class: 'text' }, fault.text));
      list.appendChild(item);
    }
  }

  /// Rebuilds the picked table's rows for the current picks (values arrive with the next event).
  syncRows() {
    const body = byId('picked').tBodies[0];
    const keys = this.picks.keys;
    for (const [key, row] of this.rows) {
      if (!keys.includes(key)) {
        row.tr.remove();
        this.rows.delete(key);
        this.signalAges.delete(key);
      }
    }
    for (const key of keys) {
      if (!this.rows.has(key)) this.rows.set(key, this.makeRow(key));
      body.appendChild(this.rows.get(key).tr);  // keeps the picks' order
    }
    for (const [key, row] of this.rows) {
      row.plot.checked = this.picks.plotted.has(key);
      row.plot.disabled = !row.plot.checked && this.picks.plotted.size >= this.picks.maxPlotted;
    }
    byId('picked-empty').hidden = keys.length > 0;
    setText(byId('picked-count'), keys.length ? `(${keys.length} of at most ${this.picks.maxSignals})` : '');
  }

  makeRow(key) {
    const info = this.catalog.get(key) || {};
    const tr = el('tr', { 'data-key': key });
    const plotCell = el('td');
    const plot = el('input', { type: 'checkbox', class: 'plot-toggle', title: 'plot this signal' });
    plot.addEventListener('change', () => this.picks.setPlotted(key, plot.checked));
    plotCell.appendChild(plot);
    const name = el('td', { class: 'key', title: info.comment || key });
    name.appendChild(el('span', { class: 'signal-name' }, info.signal || key.split('.').pop()));
    if (info.unit) name.appendChild(el('span', { class: 'unit dim' }, ` [${info.unit}]`));
    name.appendChild(el('span', { class: 'dim path' }, ` ${key}`));
    const value = el('td', { class: 'value' });
    const raw = el('td', { class: 'raw dim' });
    const status = el('td', { class: 'status', 'data-status': 'NotConnected' }, 'waiting');
    const age = el('td', { class: 'age dim' });
    const removeCell = el('td');
    const remove = el('button', { type: 'button', class: 'remove', title: 'remove' }, '×');
    remove.addEventListener('click', () => this.picks.remove(key));
    removeCell.appendChild(remove);
    for (const cell of [plotCell, name, value, raw, status, age, removeCell]) tr.appendChild(cell);
    return { tr, plot, value, raw, status, age };
  }

  renderSignal(signal, now) {
    const row = this.rows.get(signal.key);
    if (!row) return;
    const info = this.catalog.get(signal.key) || {};
    // vcu-web's text (value-table text or number with unit); the catalog fills in what it lacks
    let text = signal.text ?? '';
    const tableText = info.values && typeof signal.value === 'number' ? info.values[String(signal.value)] : undefined;
    if (tableText !== undefined && !text.includes(tableText)) text = tableText;
    if (!text && typeof signal.value === 'number') text = `${formatNumber(signal.value)}${info.unit ? ' ' + info.unit : ''}`;
    setText(row.value, signal.value === null ? '—' : text);
    setText(row.raw, typeof signal.value === 'number' && (tableText !== undefined || text !== formatNumber(signal.value))
      ? formatNumber(signal.value) : '');
    setText(row.status, statusLabel(signal.status));
    setAttr(row.status, 'data-status', signal.status ?? 'NotConnected');
    setAttr(row.tr, 'data-status', signal.status ?? 'NotConnected');
    if (typeof signal.ageMs === 'number') this.signalAges.set(signal.key, { ageMs: signal.ageMs, receivedAt: now });
    else this.signalAges.delete(signal.key);
  }

  /// Keeps "since" and "age" counting between events.
  tick() {
    const now = performance.now();
    const elapsed = (since) => (since ? since.seconds + (now - since.receivedAt) / 1000 : undefined);
    if (this.stateNote) {
      const silent = this.writerSilent ? ` for ${formatDuration(elapsed(this.writerSilent))}` : '';
      setText(byId('fsm-since'), `${this.stateNote.replace(/:.*$/, '')}${silent}: last state, not current`);
    } else {
      setText(byId('fsm-since'), this.stateSince ? `for ${formatDuration(elapsed(this.stateSince))}` : '');
    }
    const faults = byId('faults').children;
    for (let i = 0; i < faults.length; ++i) {
      const since = faults[i].querySelector('.since');
      if (since) setText(since, formatDuration(elapsed(this.faultSince[i])));
    }
    for (const [key, row] of this.rows) {
      const age = this.signalAges.get(key);
      setText(row.age, age ? formatAge(age.ageMs + (now - age.receivedAt)) : '');
    }
  }
}

/// How long ago `sinceUnixMs` was at the server's time `t` (both the VCU's clock, so a laptop
/// whose clock is off still shows the right duration), as {seconds, receivedAt} for tick();
/// `sinceS` (seconds) when vcu-web sends a duration instead. Null when neither is given.
function sinceSeconds(t, sinceUnixMs, sinceS, receivedAt) {
  if (typeof sinceUnixMs === 'number' && typeof t === 'number') {
    return { seconds: Math.max(0, (t - sinceUnixMs) / 1000), receivedAt };
  }
  if (typeof sinceS === 'number') return { seconds: sinceS, receivedAt };
  return null;
}

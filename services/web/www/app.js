// vcu-web's page: loads /api/info and /api/catalog, then wires the parts together:
//   stream.js      the EventSource on /api/live (reconnects by itself; #connection)
//   live.js        header, faults and the picked-signals table
//   plot.js        the canvas plot of up to maxPlotted picked signals
//   tree.js        the signal tree and its search
//   commands.js    login, operator switches, SetSignal / schedule / fault reset
//   recordings.js  recordings, uploads and the report frame
// The picked and plotted signals are kept in localStorage per instance, so a reload (or a
// vcu-web restart) shows the same signals.

import { getJson } from './api.js';
import { byId, setAttr, setText } from './dom.js';
import { Commands } from './commands.js';
import { LiveView } from './live.js';
import { LivePlot } from './plot.js';
import { Recordings } from './recordings.js';
import { LiveStream } from './stream.js';
import { SignalTree } from './tree.js';

/// The picked signals (in pick order) and which of them are plotted.
class Picks {
  constructor(storageKey, catalog, maxSignals, maxPlotted, onChange) {
    this.storageKey = storageKey;
    this.maxSignals = maxSignals;
    this.maxPlotted = maxPlotted;
    this.onChange = onChange;
    this.keys = [];
    this.plotted = new Set();
    try {
      const saved = JSON.parse(localStorage.getItem(storageKey) || '{}');
      this.keys = (Array.isArray(saved.keys) ? saved.keys : []).filter((k) => catalog.has(k)).slice(0, maxSignals);
      for (const key of Array.isArray(saved.plotted) ? saved.plotted : []) {
        if (this.keys.includes(key) && this.plotted.size < maxPlotted) this.plotted.add(key);
      }
    } catch (e) {
      this.keys = [];
    }
  }

  toggle(key) {
    if (this.keys.includes(key)) {
      this.remove(key);
      return;
    }
    if (this.keys.length >= this.maxSignals) {
      setText(byId('catalog-status'), `at most ${this.maxSignals} signals at once: remove one first`);
      return;
    }
    this.keys.push(key);
    if (this.plotted.size < this.maxPlotted) this.plotted.add(key);
    this.changed(true);
  }

  remove(key) {
    this.keys = this.keys.filter((k) => k !== key);
    this.plotted.delete(key);
    this.changed(true);
  }

  setPlotted(key, on) {
    if (on && this.plotted.size < this.maxPlotted) this.plotted.add(key);
    else this.plotted.delete(key);
    this.changed(false);
  }

  /// Plotted keys in pick order.
  plottedKeys() {
    return this.keys.filter((k) => this.plotted.has(k));
  }

  changed(keysChanged) {
    try {
      localStorage.setItem(this.storageKey, JSON.stringify({ keys: this.keys, plotted: [...this.plotted] }));
    } catch (e) {
      // private mode: picks last until the page is closed
    }
    this.onChange(keysChanged);
  }
}

function setupTabs() {
  for (const tab of document.querySelectorAll('#tabs .tab')) {
    tab.addEventListener('click', () => {
      for (const other of document.querySelectorAll('#tabs .tab')) {
        other.classList.toggle('active', other === tab);
        byId(other.getAttribute('data-tab')).hidden = other !== tab;
      }
      if (tab.id === 'tab-recordings') app.recordings.refresh();
    });
  }
}

function showConnection(state, detail) {
  const node = byId('connection');
  setText(node, state);
  setAttr(node, 'data-state', state);
  setAttr(node, 'data-status', state === 'connected' ? 'Ready' : state === 'reconnecting' ? 'Stale' : 'NotConnected');
  setAttr(node, 'title', detail || state);
  document.body.classList.toggle('offline', state !== 'connected');
}

/// GET /api/info until vcu-web answers (the page may load while it restarts).
async function loadInfo() {
  for (let attempt = 0; ; ++attempt) {
    const answer = await getJson('/api/info');
    if (answer.status === 200 && answer.body) return answer.body;
    showConnection('connecting', answer.error);
    await new Promise((resolve) => setTimeout(resolve, Math.min(1000 * (attempt + 1), 5000)));
  }
}

async function loadCatalog() {
  for (let attempt = 0; ; ++attempt) {
    const answer = await getJson('/api/catalog');
    if (answer.status === 200 && answer.body && Array.isArray(answer.body.signals)) return answer.body.signals;
    setText(byId('catalog-status'), `cannot load the signals: ${answer.error}`);
    await new Promise((resolve) => setTimeout(resolve, Math.min(1000 * (attempt + 1), 5000)));
  }
}

function showInfo(info) {
  setText(byId('instance'), info.instance || '');
  setAttr(byId('instance'), 'title', [info.instance, info.vehicle, info.version && `openvcu ${info.version}`].filter(Boolean).join(' · '));
  document.title = info.instance ? `openvcu ${info.instance}` : 'openvcu';
  byId('login-form').classList.toggle('unavailable', info.loginAvailable === false);
  if (info.loginAvailable === false) setText(byId('login-error'), 'logins are not configured: read-only');
}

const app = {};
let updates = 0;

async function main() {
  showConnection('connecting', 'loading');
  setupTabs();
  app.recordings = new Recordings();
  app.commands = new Commands(null);
  const info = await loadInfo();
  showInfo(info);
  app.commands.setUser(info.user);
  const signals = await loadCatalog();
  const catalog = new Map(signals.map((s) => [s.key, s]));
  app.commands.catalog = catalog;
  fillDatalists(signals);

  const maxSignals = Number(info.maxSignals) > 0 ? Number(info.maxSignals) : 32;
  const maxPlotted = Number(info.maxPlotted) > 0 ? Number(info.maxPlotted) : 4;
  const picks = new Picks(`openvcu.picks.${info.instance || ''}`, catalog, maxSignals, maxPlotted, (keysChanged) => {
    app.live.syncRows();
    app.plot.setKeys(picks.plottedKeys());
    app.tree.markPicked(picks.keys);
    if (keysChanged) app.stream.open(picks.keys);
  });
  app.live = new LiveView(catalog, picks);
  app.plot = new LivePlot(byId('plot'), catalog);
  app.tree = new SignalTree(signals, (key) => picks.toggle(key));
  app.stream = new LiveStream({
    onUpdate: (update) => {
      updates += 1;
      setAttr(byId('connection'), 'data-updates', updates);  // for the browser test and the curious
      app.live.render(update);
      app.plot.push(update);
      app.commands.renderOperator(update.operator);
    },
    onState: showConnection,
    onReconnected: async () => {
      // a restarted vcu-web has forgotten every session
      const answer = await getJson('/api/info');
      if (answer.status === 200 && answer.body) {
        showInfo(answer.body);
        app.commands.setUser(answer.body.user);
      }
    },
    onRefused: (status, error) => setText(byId('catalog-status'), `live stream refused: ${error}`),
  });
  app.live.syncRows();
  app.plot.setKeys(picks.plottedKeys());
  app.tree.markPicked(picks.keys);
  app.stream.open(picks.keys);
}

function fillDatalists(signals) {
  const keys = byId('signal-keys');
  const messages = byId('message-keys');
  const seen = new Set();
  for (const signal of signals) {
    if (signal.direction !== 'rx') {
      const option = document.createElement('option');
      option.value = signal.key;
      keys.appendChild(option);
    }
    if (signal.direction === 'tx' && signal.message && !seen.has(signal.message)) {
      seen.add(signal.message);
      const option = document.createElement('option');
      option.value = signal.message;
      messages.appendChild(option);
    }
  }
}

main();

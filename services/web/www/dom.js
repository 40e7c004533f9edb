// Small DOM and formatting helpers. Text from the server (names, reasons, comments) only ever
// goes into textContent or attributes, never into innerHTML.

/// el('li', {class: 'leaf', 'data-key': key}, 'text') -> <li class="leaf" data-key="...">text</li>
export function el(tag, attributes = {}, text = undefined) {
  const node = document.createElement(tag);
  for (const [name, value] of Object.entries(attributes)) {
    if (value === undefined || value === null || value === false) continue;
    node.setAttribute(name, value === true ? '' : String(value));
  }
  if (text !== undefined && text !== null) node.textContent = String(text);
  return node;
}

export function byId(id) {
  return document.getElementById(id);
}

/// Sets textContent only when it differs (keeps the DOM quiet at 20 updates a second).
export function setText(node, text) {
  const value = text === undefined || text === null ? '' : String(text);
  if (node.textContent !== value) node.textContent = value;
}

export function setAttr(node, name, value) {
  const text = String(value);
  if (node.getAttribute(name) !== text) node.setAttribute(name, text);
}

export function clear(node) {
  while (node.firstChild) node.removeChild(node.firstChild);
}

/// The statuses of docs/design/web.md ("Ready", "Stale", "NotConnected", "Error") as shown.
export function statusLabel(status) {
  switch (status) {
    case 'Ready': return 'ready';
    case 'Stale': return 'stale';
    case 'NotConnected': return 'not connected';
    case 'Error': return 'error';
    default: return status ? String(status) : '?';
  }
}

/// 12.3 -> "12 s", 184 -> "3 min 04 s", 7300 -> "2 h 01 min".
export function formatDuration(seconds) {
  if (typeof seconds !== 'number' || !isFinite(seconds) || seconds < 0) return '';
  const s = Math.floor(seconds);
  if (s < 60) return `${s} s`;
  if (s < 3600) return `${Math.floor(s / 60)} min ${String(s % 60).padStart(2, '0')} s`;
  return `${Math.floor(s / 3600)} h ${String(Math.floor((s % 3600) / 60)).padStart(2, '0')} min`;
}

/// 250 -> "250 ms", 4200 -> "4.2 s", 600000 -> "10 min 00 s".
export function formatAge(ms) {
  if (typeof ms !== 'number' || !isFinite(ms) || ms < 0) return '';
  if (ms < 1000) return `${Math.round(ms)} ms`;
  if (ms < 60000) return `${(ms / 1000).toFixed(1)} s`;
  return formatDuration(ms / 1000);
}

/// 1536 -> "1.5 kB" (powers of 1000, as ls -h --si).
export function formatBytes(bytes) {
  if (typeof bytes !== 'number' || !isFinite(bytes)) return '';
  const units = ['B', 'kB', 'MB', 'GB', 'TB'];
  let value = bytes;
  let unit = 0;
  while (value >= 1000 && unit < units.length - 1) {
    value /= 1000;
    unit += 1;
  }
  return unit === 0 ? `${value} B` : `${value.toFixed(value < 10 ? 1 : 0)} ${units[unit]}`;
}

/// A plain number as the VCU shows it: up to 3 decimals, no trailing zeros.
export function formatNumber(value) {
  if (typeof value !== 'number' || !isFinite(value)) return '';
  if (Number.isInteger(value)) return String(value);
  return String(Number(value.toFixed(3)));
}

export function formatTime(unixMs) {
  if (typeof unixMs !== 'number' || !isFinite(unixMs)) return '';
  const date = new Date(unixMs);
  const pad = (n) => String(n).padStart(2, '0');
  return `${date.getFullYear()}-${pad(date.getMonth() + 1)}-${pad(date.getDate())} ` +
         `${pad(date.getHours())}:${pad(date.getMinutes())}:${pad(date.getSeconds())}`;
}

// The signal tree of GET /api/catalog, shaped like the HMI's DBC tree: bus -> node ->
// message -> signal for bus signals, "internal" -> group -> signal for internal ones. A click
// on a signal picks it (or un-picks it). The search box filters on key, unit and comment
// (every word must match) and opens the branches that hold matches.

import { byId, clear, el, setText } from './dom.js';

const DIRECTION_BADGE = { rx: 'rx', tx: 'tx', internal: 'int' };

export class SignalTree {
  /// onToggle(key): called when a signal is clicked
  constructor(signals, onToggle) {
    this.onToggle = onToggle;
    this.leaves = [];   // {node, text, key}
    this.branches = []; // <details> elements, deepest first
    this.build(signals);
    const search = byId('signal-search');
    let timer = null;
    const later = () => {
      clearTimeout(timer);
      timer = setTimeout(() => this.filter(search.value), 120);
    };
    search.addEventListener('input', later);
    search.addEventListener('search', later);  // the field's clear button
  }

  build(signals) {
    const root = byId('signal-tree');
    clear(root);
    // path -> {details, list}
    const branches = new Map();
    const branch = (path, label, parentList, depth) => {
      const id = path.join('\u0000');
      if (branches.has(id)) return branches.get(id);
      const details = el('details', { 'data-path': path.join('/'), 'data-depth': depth });
      details.appendChild(el('summary', {}, label));
      const list = el('ul');
      details.appendChild(list);
      const item = el('li', { class: 'branch' });
      item.appendChild(details);
      parentList.appendChild(item);
      const entry = { details, list, depth };
      branches.set(id, entry);
      return entry;
    };
    const top = el('ul', { class: 'tree-root' });
    root.appendChild(top);
    for (const signal of signals) {
      let path;
      if (signal.direction === 'internal') {
        path = ['internal', signal.group || signal.key.split('.')[1] || ''];
      } else {
        path = [signal.bus || '?', signal.node || '?', signal.message || '?'];
      }
      let parent = { list: top };
      for (let depth = 0; depth < path.length; ++depth) {
        parent = branch(path.slice(0, depth + 1), path[depth], parent.list, depth);
      }
      const name = signal.direction === 'internal' ? signal.key.split('.').slice(2).join('.') || signal.key
                                                   : signal.signal || signal.key;
      const leaf = el('li', { class: 'leaf', 'data-key': signal.key, title: describe(signal), tabindex: 0 });
      leaf.appendChild(el('span', { class: `badge ${signal.direction}` }, DIRECTION_BADGE[signal.direction] || ''));
      leaf.appendChild(el('span', { class: 'name' }, name));
      if (signal.unit) leaf.appendChild(el('span', { class: 'unit dim' }, signal.unit));
      leaf.addEventListener('click', () => this.onToggle(signal.key));
      leaf.addEventListener('keydown', (event) => {
        if (event.key === 'Enter' || event.key === ' ') {
          event.preventDefault();
          this.onToggle(signal.key);
        }
      });
      parent.list.appendChild(leaf);
      const text = [signal.key, signal.unit, signal.comment, ...Object.values(signal.values || {})].join(' ').toLowerCase();
      this.leaves.push({ node: leaf, text, key: signal.key });
    }
    this.branches = [...branches.values()].sort((a, b) => b.depth - a.depth);
    // the top level (buses, internal) starts open
    for (const entry of this.branches) if (entry.depth === 0) entry.details.open = true;
    setText(byId('catalog-status'), `${signals.length} signals`);
  }

  filter(term) {
    const words = term.toLowerCase().split(/\s+/).filter(Boolean);
    let shown = 0;
    for (const leaf of this.leaves) {
      const match = words.every((word) => leaf.text.includes(word));
      leaf.node.hidden = !match;
      if (match) shown += 1;
    }
    // deepest first: a branch is shown when anything under it is
    for (const entry of this.branches) {
      const visible = [...entry.list.children].some((child) => !child.hidden);
      entry.details.parentElement.hidden = !visible;
      if (words.length) entry.details.open = visible && shown <= 400;
      else entry.details.open = entry.depth === 0;
    }
    setText(byId('catalog-status'), words.length ? `${shown} of ${this.leaves.length} signals match` : `${this.leaves.length} signals`);
  }

  markPicked(keys) {
    const picked = new Set(keys);
    for (const leaf of this.leaves) leaf.node.classList.toggle('picked', picked.has(leaf.key));
  }
}

function describe(signal) {
  const lines = [signal.key];
  if (signal.comment) lines.push(signal.comment);
  if (typeof signal.min === 'number' && typeof signal.max === 'number' && signal.min < signal.max) {
    lines.push(`range ${signal.min} .. ${signal.max}${signal.unit ? ' ' + signal.unit : ''}`);
  }
  const values = Object.entries(signal.values || {});
  if (values.length) lines.push(values.slice(0, 12).map(([v, t]) => `${v} ${t}`).join(', ') + (values.length > 12 ? ', …' : ''));
  return lines.join('\n');
}

// Recordings and traces (docs/design/web.md): the folders `vcu record` wrote on the VCU and
// the logs uploaded from a browser, each with its summary, its report (shown in
// #report-frame, a sandboxed iframe) and, for recordings, a .tar.gz download. An upload is
// sent as the raw file (vcu-web streams it to disk) and its report opens when it is done.

import { entryPath, getJson, postFile } from './api.js';
import { byId, clear, el, formatBytes, formatNumber, formatTime, setAttr, setText } from './dom.js';

export class Recordings {
  constructor() {
    byId('recordings-refresh').addEventListener('click', () => this.refresh());
    byId('upload-button').addEventListener('click', () => this.upload());
  }

  async refresh() {
    const status = byId('recordings-status');
    setText(status, 'loading…');
    const answer = await getJson('/api/recordings');
    if (answer.status !== 200 || !answer.body) {
      setText(status, `cannot list the recordings: ${answer.error}`);
      return;
    }
    const body = byId('recordings').tBodies[0];
    clear(body);
    const recordings = Array.isArray(answer.body.recordings) ? answer.body.recordings : [];
    const uploads = Array.isArray(answer.body.uploads) ? answer.body.uploads : [];
    for (const entry of recordings) body.appendChild(this.row('recordings', entry));
    for (const entry of uploads) body.appendChild(this.row('uploads', entry));
    setText(status, `${recordings.length} recordings, ${uploads.length} uploaded logs`);
  }

  /// name (files and summary below it) | size | modified | report, download, summary
  row(kind, entry) {
    const tr = el('tr', { 'data-name': entry.name, 'data-kind': kind });
    const nameCell = el('td', { class: 'name' });
    nameCell.appendChild(el('div', { class: 'entry-name' }, entry.name));
    const files = Array.isArray(entry.files) ? entry.files : [];
    nameCell.appendChild(el('div', { class: 'files dim' }, files.map((f) => `${f.name} (${formatBytes(f.bytes)})`).join(', ')));
    const summary = el('div', { class: 'summary-text' });
    nameCell.appendChild(summary);
    tr.appendChild(nameCell);
    tr.appendChild(el('td', { class: 'size' }, formatBytes(entry.bytes)));
    tr.appendChild(el('td', { class: 'modified' }, formatTime(entry.modifiedUnixMs)));
    const actions = el('td', { class: 'actions' });
    const report = el('a', { href: entryPath(kind, entry.name, 'report'), class: 'report-link' }, 'report');
    report.addEventListener('click', (event) => {
      event.preventDefault();
      this.openReport(kind, entry.name);
    });
    actions.appendChild(report);
    if (kind === 'recordings') {
      actions.appendChild(el('a', {
        href: entryPath(kind, entry.name, 'archive'),
        download: `${entry.name}.tar.gz`,
        class: 'download-link',
      }, 'download'));
    }
    const summaryButton = el('button', { type: 'button', class: 'summary-button' }, 'summary');
    summaryButton.addEventListener('click', async () => {
      setText(summary, 'analysing…');
      setText(summary, await this.summaryText(kind, entry.name));
    });
    actions.appendChild(summaryButton);
    tr.appendChild(actions);
    return tr;
  }

  async summaryText(kind, name) {
    const answer = await getJson(entryPath(kind, name, 'summary'));
    if (answer.status !== 200 || !answer.body) return `no summary: ${answer.error}`;
    const s = answer.body;
    const findings = s.findings || {};
    const buses = Array.isArray(s.buses) ? s.buses.map((b) => (typeof b === 'string' ? b : b.name)).filter(Boolean) : [];
    return `${s.frames} frames, ${formatNumber(s.durationS)} s` + (buses.length ? ` on ${buses.join(', ')}` : '') +
           `; ${findings.errors ?? '?'} errors, ${findings.warnings ?? '?'} warnings`;
  }

  openReport(kind, name) {
    const path = entryPath(kind, name, 'report');
    byId('report-frame').src = path;
    setAttr(byId('report-frame'), 'data-name', name);
    setText(byId('report-name'), name);
    const link = byId('report-link');
    link.href = path;
    link.hidden = false;
  }

  async upload() {
    const result = byId('upload-result');
    const file = byId('upload-file').files[0];
    if (!file) {
      setText(result, 'choose a log file first');
      setAttr(result, 'data-outcome', 'error');
      return;
    }
    setText(result, `uploading ${file.name} (${formatBytes(file.size)})…`);
    setAttr(result, 'data-outcome', 'pending');
    byId('upload-button').disabled = true;
    const answer = await postFile(`/api/uploads?name=${encodeURIComponent(file.name)}`, file);
    byId('upload-button').disabled = !document.body.classList.contains('logged-in');  // a logout meanwhile
    if (answer.status !== 200 || !answer.body || typeof answer.body.name !== 'string') {
      setText(result, `not uploaded: ${answer.error || 'unexpected answer'}`);
      setAttr(result, 'data-outcome', 'error');
      return;
    }
    const name = answer.body.name;
    setText(result, `uploaded as ${name}; analysing…`);
    this.openReport('uploads', name);
    this.refresh();
    setText(result, `uploaded as ${name}: ${await this.summaryText('uploads', name)}`);
    setAttr(result, 'data-outcome', 'done');
  }
}

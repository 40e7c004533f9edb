// Logins and commands (docs/design/web.md: POST /api/login, /api/logout, /api/command).
// Reading needs no login; every command button is disabled until a login succeeded. The
// VCU's answer is shown in #command-result as the HMI shows it: "accepted by vcu-fsm" or
// "refused by vcu-fsm: <reason>"; a command vcu-web did not send says "not sent: <reason>".

import { postJson } from './api.js';
import { byId, clear, el, setAttr, setText } from './dom.js';

export class Commands {
  /// onUserChanged(user): after a login, a logout or a lost session
  /// catalog: key -> catalog entry (value texts of the switches), may be set later
  constructor(onUserChanged) {
    this.catalog = new Map();
    this.user = null;
    this.onUserChanged = onUserChanged;
    this.operatorKeys = '';
    this.operatorState = new Map();  // key -> {on, enabled}
    byId('login-form').addEventListener('submit', (event) => {
      event.preventDefault();
      this.login();
    });
    byId('logout-button').addEventListener('click', () => this.logout());
    byId('set-form').addEventListener('submit', (event) => {
      event.preventDefault();
      const key = byId('set-key').value.trim();
      this.send({ kind: 'set', key, value: parseValue(byId('set-value').value) }, `set ${key}`);
    });
    byId('clear-button').addEventListener('click', () => {
      const key = byId('set-key').value.trim();
      this.send({ kind: 'clear', key, value: 0 }, `clear override of ${key}`);
    });
    const scheduleKey = () => byId('schedule-key').value.trim();
    byId('schedule-enable').addEventListener('click', () =>
      this.send({ kind: 'scheduleEnable', key: scheduleKey(), value: 1 }, `enable ${scheduleKey()}`));
    byId('schedule-disable').addEventListener('click', () =>
      this.send({ kind: 'scheduleEnable', key: scheduleKey(), value: 0 }, `disable ${scheduleKey()}`));
    byId('schedule-form').addEventListener('submit', (event) => {
      event.preventDefault();
      const cycle = Number(byId('schedule-cycle').value);
      this.send({ kind: 'scheduleCycle', key: scheduleKey(), value: cycle }, `cycle of ${scheduleKey()}: ${cycle} ms`);
    });
    byId('fault-reset-button').addEventListener('click', () =>
      this.send({ kind: 'faultReset', key: '', value: 1 }, 'reset faults'));
    this.setUser(null);
  }

  setUser(user) {
    this.user = typeof user === 'string' && user ? user : null;
    const loggedIn = this.user !== null;
    byId('login-form').hidden = loggedIn;
    byId('logged-in').hidden = !loggedIn;
    setText(byId('whoami'), this.user ?? '');
    byId('command-hint').hidden = loggedIn;
    document.body.classList.toggle('logged-in', loggedIn);
    for (const button of document.querySelectorAll('.needs-login')) button.disabled = !loggedIn;
    this.refreshOperatorButtons();
    if (this.onUserChanged) this.onUserChanged(this.user);
  }

  async login() {
    const user = byId('login-user').value.trim();
    const password = byId('login-password').value;
    setText(byId('login-error'), '');
    byId('login-button').disabled = true;
    const answer = await postJson('/api/login', { user, password });
    byId('login-button').disabled = false;
    byId('login-password').value = '';
    if (answer.status === 200 && answer.body && typeof answer.body.user === 'string') {
      this.setUser(answer.body.user);
    } else {
      setText(byId('login-error'), answer.error || `login failed (HTTP ${answer.status})`);
    }
  }

  async logout() {
    await postJson('/api/logout', {});
    this.setUser(null);
  }

  /// Operator switches from the update event: one button per switch, rebuilt only when the
  /// set of switches changes (a click is never lost to a re-render).
  renderOperator(switches) {
    if (!Array.isArray(switches)) return;
    const box = byId('operator');
    const keys = switches.map((s) => s.key).join(',');
    if (keys !== this.operatorKeys) {
      this.operatorKeys = keys;
      clear(box);
      for (const entry of switches) {
        const button = el('button', { type: 'button', class: 'switch', 'data-key': entry.key });
        button.appendChild(el('span', { class: 'label' }));
        button.appendChild(el('span', { class: 'state' }));
        button.addEventListener('click', () => this.toggle(entry.key, button));
        box.appendChild(button);
      }
    }
    switches.forEach((entry, i) => {
      const button = box.children[i];
      setText(button.querySelector('.label'), entry.label ?? entry.key);
      setText(button.querySelector('.state'), entry.stateText || this.valueText(entry));
      setAttr(button, 'data-on', entry.on ? 'true' : 'false');
      setAttr(button, 'title', `${entry.key}: press to switch ${entry.on ? 'off' : 'on'}`);
      this.operatorState.set(entry.key, {
        on: !!entry.on,
        enabled: entry.enabled !== false,
        onValue: typeof entry.onValue === 'number' ? entry.onValue : 1,
      });
    });
    this.refreshOperatorButtons();
  }

  /// "Start" / "Stop" from the catalog's value table when vcu-web sends no stateText.
  valueText(entry) {
    const values = (this.catalog.get(entry.key) || {}).values || {};
    const value = entry.on ? (typeof entry.onValue === 'number' ? entry.onValue : 1) : 0;
    return values[String(value)] ?? (entry.on ? 'on' : 'off');
  }

  refreshOperatorButtons() {
    for (const button of byId('operator').children) {
      const state = this.operatorState.get(button.getAttribute('data-key'));
      button.disabled = this.user === null || !state || !state.enabled;
    }
  }

  toggle(key, button) {
    const state = this.operatorState.get(key);
    if (!state) return;
    const label = button.querySelector('.label').textContent;
    const value = state.on ? 0 : state.onValue;
    const text = ((this.catalog.get(key) || {}).values || {})[String(value)] ?? (state.on ? 'off' : 'on');
    this.send({ kind: 'operator', key, value }, `${label}: ${text}`);
  }

  async send(command, description) {
    const result = byId('command-result');
    setText(byId('command-what'), description);
    setText(result, 'sending…');
    setAttr(result, 'data-outcome', 'pending');
    const answer = await postJson('/api/command', command);
    let text;
    let outcome;
    if (answer.status === 200 && answer.body && typeof answer.body.accepted === 'boolean') {
      const responder = answer.body.responder || 'the VCU';
      if (answer.body.accepted) {
        text = `accepted by ${responder}`;
        outcome = 'accepted';
      } else {
        text = `refused by ${responder}: ${answer.body.reason || 'no reason given'}`;
        outcome = 'refused';
      }
    } else if (answer.status === 401) {
      text = `not sent: log in first (${answer.error})`;
      outcome = 'error';
      this.setUser(null);
    } else if (answer.status === 504) {
      text = `no answer in time, nothing applied: ${answer.error}`;
      outcome = 'error';
    } else {
      text = `not sent: ${answer.error || 'unexpected answer'}`;
      outcome = 'error';
    }
    setText(result, text);
    setAttr(result, 'data-outcome', outcome);
  }
}

/// "12.5" -> 12.5, "Start" -> "Start" (a value text), "" -> NaN (vcu-web refuses it).
function parseValue(text) {
  const trimmed = text.trim();
  if (trimmed === '') return NaN;
  const number = Number(trimmed);
  return Number.isFinite(number) ? number : trimmed;
}

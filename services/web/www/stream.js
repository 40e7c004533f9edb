// The live stream: one EventSource on /api/live?signals=... (docs/design/web.md, "update"
// events pushed by vcu-web), reopened when the picked signals change and kept alive across
// vcu-web restarts.
//
// EventSource retries by itself after a network error (readyState CONNECTING). When it gives
// up (readyState CLOSED: the server answered with something other than an event stream, or
// the browser stopped retrying), the stream asks the server what is wrong with an ordinary
// fetch of the same URL: not reachable -> try again after a back-off (1, 2, 4, 5, 5, ... s);
// an error answer (400 naming unknown keys, 503 too many streams) -> reported through
// onRefused and tried again after the longest back-off.
//
// Connection states reported through onState: "connecting" (first open), "connected",
// "reconnecting" (lost, trying again).

const BACKOFF_MS = [1000, 2000, 4000, 5000];

export class LiveStream {
  /// handlers: {onUpdate(update), onState(state, detail), onReconnected(), onRefused(status, error)}
  constructor(handlers) {
    this.handlers = handlers;
    this.source = null;
    this.keys = [];
    this.state = 'connecting';
    this.everConnected = false;
    this.lost = false;
    this.attempt = 0;
    this.retryTimer = null;
    this.badEvents = 0;
  }

  url() {
    const query = this.keys.length ? `?signals=${encodeURIComponent(this.keys.join(','))}` : '';
    return `/api/live${query}`;
  }

  /// (Re)opens the stream for `keys` (the picked signals).
  open(keys) {
    this.keys = keys.slice();
    this.close();
    this.connect();
  }

  close() {
    if (this.retryTimer !== null) {
      clearTimeout(this.retryTimer);
      this.retryTimer = null;
    }
    if (this.source) {
      this.source.close();
      this.source = null;
    }
  }

  connect() {
    const source = new EventSource(this.url());
    this.source = source;
    source.addEventListener('open', () => {
      if (source !== this.source) return;
      this.attempt = 0;
      const wasLost = this.lost;
      this.lost = false;
      this.everConnected = true;
      this.setState('connected', '');
      if (wasLost && this.handlers.onReconnected) this.handlers.onReconnected();
    });
    source.addEventListener('update', (event) => {
      if (source !== this.source) return;
      let update;
      try {
        update = JSON.parse(event.data);
      } catch (e) {
        this.badEvents += 1;
        return;
      }
      this.handlers.onUpdate(update);
    });
    source.addEventListener('error', () => {
      if (source !== this.source) return;
      this.lost = true;
      if (source.readyState === EventSource.CONNECTING) {
        this.setState(this.everConnected ? 'reconnecting' : 'connecting', 'the browser retries');
        return;
      }
      // CLOSED: the browser gave up; find out why and try again ourselves.
      source.close();
      this.source = null;
      this.setState(this.everConnected ? 'reconnecting' : 'connecting', 'trying again');
      this.probe();
    });
  }

  async probe() {
    const url = this.url();
    const controller = new AbortController();
    let status = 0;
    let error = '';
    try {
      const response = await fetch(url, { signal: controller.signal, credentials: 'same-origin' });
      status = response.status;
      if (!response.ok) {
        try {
          const body = await response.json();
          error = body && typeof body.error === 'string' ? body.error : `HTTP ${status}`;
        } catch (e) {
          error = `HTTP ${status}`;
        }
      }
    } catch (e) {
      status = 0;
    } finally {
      controller.abort();
    }
    if (url !== this.url() || this.source) return;  // reopened meanwhile
    let delay;
    if (status === 0 || status === 200) {
      delay = status === 200 ? 0 : BACKOFF_MS[Math.min(this.attempt, BACKOFF_MS.length - 1)];
      this.attempt += 1;
    } else {
      if (this.handlers.onRefused) this.handlers.onRefused(status, error);
      this.setState(this.everConnected ? 'reconnecting' : 'connecting', error);
      delay = BACKOFF_MS[BACKOFF_MS.length - 1];
    }
    this.retryTimer = setTimeout(() => {
      this.retryTimer = null;
      if (!this.source) this.connect();
    }, delay);
  }

  setState(state, detail) {
    this.state = state;
    this.handlers.onState(state, detail);
  }
}

"""HTTP helpers of the vcu-web tests (python3 standard library only): a client that keeps the
session cookie and sends paths exactly as written, a raw reader of the server-sent-event
stream (/api/live), and the checks' Failure.

  c = Client('127.0.0.1', 18080)
  answer = c.post_json('/api/login', {'user': 'alice', 'password': secret})   # c.session set
  stream = LiveStream(c, ['internal.fsm.state']); update = stream.next_update(10)
"""

import http.client
import json
import socket
import time
import urllib.parse


class Failure(Exception):
    pass


class Quiet(Failure):
    """No event within the time asked for."""


def check(condition, what):
    if not condition:
        raise Failure(what)


class Answer:
    def __init__(self, status, headers, body):
        self.status = status
        self.headers = headers  # lower-case name -> value (Set-Cookie: all joined by '\n')
        self.body = body

    def json(self):
        try:
            return json.loads(self.body.decode('utf-8'))
        except (UnicodeDecodeError, json.JSONDecodeError) as error:
            raise Failure(f'answer {self.status} is not JSON ({error}): {self.body[:200]!r}')

    def error(self):
        body = self.json()
        check(isinstance(body, dict) and isinstance(body.get('error'), str) and body['error'],
              f'an error answer without {{"error": "..."}}: {self.body[:200]!r}')
        return body['error']

    def __repr__(self):
        return f'HTTP {self.status} {self.body[:300]!r}'


class Client:
    """One HTTP client with the session cookie vcu-web set (if any), from `source` address."""

    def __init__(self, host, port, source='127.0.0.1'):
        self.host = host
        self.port = port
        self.source = source
        self.session = ''

    def connection(self, timeout=10):
        return http.client.HTTPConnection(self.host, self.port, timeout=timeout, source_address=(self.source, 0))

    def request(self, method, path, body=None, headers=None, timeout=20):
        """`path` is sent exactly as given (no normalisation: traversal attempts stay as written)."""
        all_headers = dict(headers or {})
        if self.session:
            all_headers['Cookie'] = f'vcu_session={self.session}'
        connection = self.connection(timeout)
        try:
            connection.request(method, path, body=body, headers=all_headers)
            response = connection.getresponse()
            data = response.read()
            names = {}
            for name, value in response.getheaders():
                key = name.lower()
                names[key] = names[key] + '\n' + value if key in names else value
            answer = Answer(response.status, names, data)
        finally:
            connection.close()
        for cookie in answer.headers.get('set-cookie', '').split('\n'):
            if cookie.startswith('vcu_session='):
                self.session = cookie.split(';', 1)[0].split('=', 1)[1]
        return answer

    def get(self, path, **kwargs):
        return self.request('GET', path, **kwargs)

    def post_json(self, path, value, **kwargs):
        body = value if isinstance(value, (bytes, str)) else json.dumps(value)
        return self.request('POST', path, body=body, headers={'Content-Type': 'application/json'}, **kwargs)


class LiveStream:
    """GET /api/live as a raw socket: reads `update` events one by one."""

    def __init__(self, client, keys):
        self.sock = socket.create_connection((client.host, client.port), timeout=10)
        query = urllib.parse.quote(','.join(keys), safe='')
        self.sock.sendall(f'GET /api/live?signals={query} HTTP/1.1\r\nHost: {client.host}\r\n'
                          f'Accept: text/event-stream\r\n\r\n'.encode())
        self.buffer = b''
        head = self._read_until(b'\r\n\r\n')
        lines = head.decode('latin-1').split('\r\n')
        self.status = int(lines[0].split()[1])
        self.headers = {l.split(':', 1)[0].lower(): l.split(':', 1)[1].strip() for l in lines[1:] if ':' in l}
        self.chunked = 'chunked' in self.headers.get('transfer-encoding', '').lower()
        self.raw = b''  # de-chunked body not yet split into events

    def _read_until(self, marker, deadline=None):
        while marker not in self.buffer:
            if deadline is not None:
                self.sock.settimeout(max(0.05, deadline - time.monotonic()))
            data = self.sock.recv(65536)
            if not data:
                raise Failure('the live stream closed')
            self.buffer += data
        head, self.buffer = self.buffer.split(marker, 1)
        return head

    def _fill(self, deadline):
        if not self.chunked:
            self.sock.settimeout(max(0.05, deadline - time.monotonic()))
            data = self.sock.recv(65536)
            if not data:
                raise Failure('the live stream closed')
            self.raw += data
            return
        size_line = self._read_until(b'\r\n', deadline)
        size = int(size_line.split(b';')[0], 16)
        while len(self.buffer) < size + 2:
            self.sock.settimeout(max(0.05, deadline - time.monotonic()))
            data = self.sock.recv(65536)
            if not data:
                raise Failure('the live stream closed')
            self.buffer += data
        self.raw += self.buffer[:size]
        self.buffer = self.buffer[size + 2:]

    def next_event(self, timeout):
        """(event name, data) of the next event, comments skipped; Failure after `timeout` s."""
        deadline = time.monotonic() + timeout
        while True:
            text = self.raw.replace(b'\r\n', b'\n')
            if b'\n\n' in text:
                block, rest = text.split(b'\n\n', 1)
                self.raw = rest
                name, data = 'message', []
                for line in block.decode('utf-8').split('\n'):
                    if line.startswith(':') or not line:
                        continue
                    field, _, value = line.partition(':')
                    value = value[1:] if value.startswith(' ') else value
                    if field == 'event':
                        name = value
                    elif field == 'data':
                        data.append(value)
                if not data and name == 'message':
                    continue  # a comment block (keep-alive)
                return name, '\n'.join(data)
            if time.monotonic() > deadline:
                raise Quiet(f'no event within {timeout} s')
            try:
                self._fill(deadline)
            except socket.timeout:
                raise Quiet(f'no event within {timeout} s')

    def next_update(self, timeout=10):
        while True:
            name, data = self.next_event(timeout)
            if name == 'update':
                try:
                    return json.loads(data)
                except json.JSONDecodeError as error:
                    raise Failure(f'an update event is not JSON ({error}): {data[:200]!r}')

    def close(self):
        self.sock.close()


def announce_body(c, path, content_type, length):
    """The status of a POST that announces `length` bytes and sends none of them: a server that
    checks its limits on the header answers at once (sending no body also keeps a connection the
    server resets from hiding the answer); one that waits for the body times out (-> Failure)."""
    sock = socket.create_connection((c.host, c.port), timeout=10)
    try:
        cookie = f'Cookie: vcu_session={c.session}\r\n' if c.session else ''
        sock.sendall((f'POST {path} HTTP/1.1\r\nHost: {c.host}\r\n{cookie}Content-Type: {content_type}\r\n'
                      f'Content-Length: {length}\r\n\r\n').encode())
        reply = b''
        while b'\r\n' not in reply:
            data = sock.recv(4096)
            if not data:
                break
            reply += data
    except socket.timeout:
        raise Failure(f'POST {path} announcing {length} bytes: no answer within 10 s (limits not checked on the header?)')
    finally:
        sock.close()
    try:
        return int(reply.split(b'\r\n', 1)[0].split()[1])
    except (IndexError, ValueError):
        raise Failure(f'POST {path} announcing {length} bytes: no status line: {reply[:100]!r}')


def expect_status(answer, statuses, what):
    statuses = statuses if isinstance(statuses, (tuple, list, set)) else (statuses,)
    check(answer.status in statuses, f'{what}: expected HTTP {"/".join(map(str, statuses))}, got {answer!r}')


def live_refusal(c, keys):
    """(status, error text) of GET /api/live for `keys`; the error is empty for a 200 stream."""
    stream = LiveStream(c, keys)
    try:
        if stream.status == 200:
            return 200, ''
        length = int(stream.headers.get('content-length', '0'))
        body = stream.buffer
        stream.sock.settimeout(5)
        while len(body) < length:
            data = stream.sock.recv(65536)
            if not data:
                break
            body += data
        try:
            return stream.status, str(json.loads(body[:length].decode('utf-8')).get('error', ''))
        except (UnicodeDecodeError, json.JSONDecodeError, AttributeError):
            raise Failure(f'/api/live refused with a body that is not {{"error"}}: {body[:200]!r}')
    finally:
        stream.close()

#!/usr/bin/python3
"""Every endpoint of docs/design/web.md against a running vcu-web, good and bad requests.

Run by web_stack_test.sh (inside tests/harness/run_isolated.sh) with the HHEA stack and
vcu-web up, the FSM in Standby:

  web_api_test.py --url http://127.0.0.1:PORT --user alice --recording drive1 \
                  --log tests/data/logs/candump_l.log
  (the password in the environment: OPENVCU_WEB_PASSWORD)
  web_api_test.py --url http://127.0.0.1:PORT --read-only MISSING_USERS_FILE
  (vcu-web started with a users file that does not exist: read-only pages, logins 503)

Python's standard library only (and web_client.py beside it). Every group of checks runs;
each prints its lines, a failed one "web_api_test: FAIL (<group>): <why>"; the last line is
"web_api_test: PASS" or "web_api_test: FAIL: N group(s): ..." (exit 1). Leaves the FSM in
Standby, no session open and one uploaded log behind.
"""

import argparse
import http.client
import io
import json
import os
import sys
import tarfile
import time
import urllib.parse

from web_client import Client, Failure, LiveStream, Quiet, announce_body, check, expect_status, live_refusal

NAME = 'web_api_test'
PASSWD_LINE = 'root:x:0:0'
FSM_KEY = 'internal.fsm.state'
START_KEY = 'internal.operator.StartStop'


def log(text):
    print(f'{NAME}: {text}', flush=True)


# ---------------------------------------------------------------------------------------------

def check_static(c):
    answer = c.get('/')
    expect_status(answer, 200, 'GET /')
    check(answer.headers.get('content-type', '').startswith('text/html'), f'GET / is not text/html: {answer.headers}')
    check(b'id="fsm-state"' in answer.body, 'GET / is not the page of services/web/www')
    csp = answer.headers.get('content-security-policy', '')
    check("default-src 'self'" in csp, f"GET / has no Content-Security-Policy default-src 'self': {csp!r}")
    for path, kind in (('/app.js', 'javascript'), ('/style.css', 'text/css')):
        answer = c.get(path)
        expect_status(answer, 200, f'GET {path}')
        check(kind in answer.headers.get('content-type', ''), f'GET {path}: content type {answer.headers.get("content-type")}')
    expect_status(c.get('/no-such-file.js'), 404, 'GET of a missing static file')
    log('static files: /, app.js, style.css served with a CSP; a missing file is 404')


def check_info(c):
    answer = c.get('/api/info')
    expect_status(answer, 200, 'GET /api/info')
    info = answer.json()
    for key in ('instance', 'vehicle', 'version', 'user', 'loginAvailable', 'maxUpdatesPerSecond', 'maxSignals', 'maxPlotted'):
        check(key in info, f'/api/info has no "{key}": {info}')
    check(info['user'] is None, f'/api/info without a session names a user: {info}')
    check(info['loginAvailable'] is True, f'/api/info: logins not available with a users file: {info}')
    check(info['instance'] == 'hhea', f'/api/info: instance {info["instance"]!r}')
    check(isinstance(info['maxUpdatesPerSecond'], (int, float)) and info['maxUpdatesPerSecond'] > 0, f'maxUpdatesPerSecond: {info}')
    check(isinstance(info['maxSignals'], int) and info['maxSignals'] >= 4, f'maxSignals: {info}')
    check(isinstance(info['maxPlotted'], int) and 1 <= info['maxPlotted'] <= info['maxSignals'], f'maxPlotted: {info}')
    log(f'info: {info}')
    return info


def check_catalog(c):
    answer = c.get('/api/catalog')
    expect_status(answer, 200, 'GET /api/catalog')
    signals = answer.json().get('signals')
    check(isinstance(signals, list) and len(signals) > 50, f'catalog: too few signals: {str(signals)[:200]}')
    by_key = {}
    for signal in signals:
        for field in ('key', 'bus', 'node', 'message', 'signal', 'unit', 'min', 'max', 'direction', 'values', 'comment'):
            check(field in signal, f'catalog entry without "{field}": {signal}')
        check(signal['direction'] in ('rx', 'tx', 'internal'), f'catalog direction: {signal}')
        if signal['direction'] == 'internal':
            check(signal['bus'] == '' and signal['node'] == '' and signal['message'] == '', f'internal with a bus: {signal}')
            check(signal.get('group') == signal['key'].split('.')[1], f'internal signal group: {signal}')
        else:
            check(signal['bus'] and signal['message'], f'a bus signal without bus/message: {signal}')
        check(signal['key'] not in by_key, f'catalog key twice: {signal["key"]}')
        by_key[signal['key']] = signal
    start = by_key.get(START_KEY)
    check(start is not None, f'{START_KEY} not in the catalog')
    check(start['values'] == {'0': 'Stop', '1': 'Start'}, f'{START_KEY} values: {start["values"]}')
    check(FSM_KEY in by_key, f'{FSM_KEY} not in the catalog')
    directions = {s['direction'] for s in signals}
    check(directions == {'rx', 'tx', 'internal'}, f'catalog directions: {directions}')
    log(f'catalog: {len(signals)} signals, {START_KEY} {start["values"]}')
    return by_key


def pick_signals(catalog):
    """internal.fsm.state, the received signal with a unit first in the catalog, a transmitted one."""
    rx = next(k for k, s in catalog.items() if s['direction'] == 'rx' and s['unit'])
    tx = next(k for k, s in catalog.items() if s['direction'] == 'tx')
    return [FSM_KEY, rx, tx]


def check_live(c, info, catalog):
    keys = pick_signals(catalog)
    stream = LiveStream(c, keys)
    try:
        check(stream.status == 200, f'/api/live: HTTP {stream.status}')
        check(stream.headers.get('content-type', '').startswith('text/event-stream'),
              f'/api/live content type: {stream.headers.get("content-type")}')
        first = stream.next_update(10)
        second = stream.next_update(10)
        for update in (first, second):
            for field in ('t', 'seq', 'header', 'faults', 'operator', 'signals'):
                check(field in update, f'update without "{field}": {str(update)[:300]}')
            header = update['header']
            for field in ('state', 'stateIndex', 'stateSinceUnixMs', 'soc', 'health', 'services'):
                check(field in header, f'update header without "{field}": {header}')
            since = header['stateSinceUnixMs']
            check(isinstance(since, (int, float)) and since <= update['t'], f'stateSinceUnixMs {since} after t {update["t"]}')
            for fault in update['faults']:
                check(set(fault) >= {'name', 'source', 'severity', 'text', 'sinceUnixMs'}, f'update fault {fault}')
            check(isinstance(header['state'], str) and header['state'], f'update: FSM state {header["state"]!r}')
            check(set(header['soc']) >= {'text', 'status'}, f'update: soc {header["soc"]}')
            check(header['health'] in ('Ready', 'Stale', 'NotConnected', 'Error'), f'update: health {header["health"]}')
            for service in header['services']:
                check(set(service) >= {'name', 'status', 'text'}, f'update: service {service}')
            check([s['key'] for s in update['signals']] == keys, f'update signals {[s["key"] for s in update["signals"]]} != {keys}')
            for signal in update['signals']:
                check(set(signal) >= {'key', 'value', 'text', 'status', 'ageMs'}, f'update signal {signal}')
                check(signal['status'] in ('Ready', 'Stale', 'NotConnected'), f'update signal status {signal}')
            operator_keys = [o['key'] for o in update['operator']]
            check(START_KEY in operator_keys, f'update operator switches {operator_keys}')
            for entry in update['operator']:
                check(set(entry) >= {'key', 'label', 'on', 'enabled', 'stateText'}, f'operator switch {entry}')
        check(second['seq'] > first['seq'], f'seq does not grow: {first["seq"]} then {second["seq"]}')
        check(second['t'] >= first['t'], f't goes back: {first["t"]} then {second["t"]}')
        fsm = next(s for s in first['signals'] if s['key'] == FSM_KEY)
        check(fsm['status'] == 'Ready' and isinstance(fsm['value'], (int, float)), f'{FSM_KEY} not Ready: {fsm}')
        log(f'live: two updates, state {first["header"]["state"]}, signals {[(s["key"], s["text"], s["status"]) for s in first["signals"]]}')
    finally:
        stream.close()

    # the cap: over 3 s, at most maxUpdatesPerSecond a second (one event of slack), on a busy
    # stream: as many transmitted signals as a page may ask for, the sequence counters (SEQ_*,
    # HHEA's HC demands: they change every cycle) first
    transmitted = [k for k, s in catalog.items() if s['direction'] == 'tx']
    busy = sorted(transmitted, key=lambda k: 'SEQ_' not in k)[: info['maxSignals']]
    limit = info['maxUpdatesPerSecond']
    stream = LiveStream(c, busy)
    try:
        check(stream.status == 200, f'/api/live with {len(busy)} keys: HTTP {stream.status}')
        stream.next_update(10)  # the first: the state when the stream opened
        start = time.monotonic()
        times = []
        while True:
            left = 3.0 - (time.monotonic() - start)
            if left <= 0:
                break
            try:
                stream.next_update(left)
            except Quiet:
                break
            times.append(time.monotonic())
        elapsed = time.monotonic() - start
        count = len(times)
        # 10 % and one event of slack for timer jitter; these signals change every 10-20 ms, so
        # a stream without the cap sends several times more
        check(count <= limit * elapsed * 1.1 + 1, f'{count} updates in {elapsed:.2f} s, more than {limit}/s')
        check(count >= limit, f'{count} updates in 3 s of {len(busy)} transmitted signals: too quiet to measure the cap')
        gaps = [b - a for a, b in zip(times, times[1:])]
        log(f'live: {count} updates in {elapsed:.2f} s of {len(busy)} transmitted signals (cap {limit}/s), '
            f'smallest gap {min(gaps) * 1000:.0f} ms')
    finally:
        stream.close()

    # refusals read through the raw stream: a server that streams instead must not hang the test
    status, error = live_refusal(c, ['no.such.Signal', FSM_KEY])
    check(status == 400, f'live with an unknown key: HTTP {status}, expected 400')
    check('no.such.Signal' in error, f'live: the 400 does not name the unknown key: {error!r}')
    many = [k for k in catalog][: info['maxSignals'] + 1]
    status, error = live_refusal(c, many)
    check(status == 400, f'live with {len(many)} keys (maxSignals {info["maxSignals"]}): HTTP {status}, expected 400')
    log(f'live: an unknown key -> 400 naming it; {len(many)} keys (more than maxSignals) -> 400 "{error}"')


def wait_state(c, predicate, what, timeout=20):
    """Reads the live stream until predicate(state) holds; returns the state."""
    stream = LiveStream(c, [FSM_KEY])
    seen = []
    try:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            update = stream.next_update(max(0.5, deadline - time.monotonic()))
            state = update['header']['state']
            if not seen or seen[-1] != state:
                seen.append(state)
            if predicate(state):
                return state, seen
    except Failure as failure:
        raise Failure(f'{what}: {failure}; states seen {seen}')
    finally:
        stream.close()
    raise Failure(f'{what}: not within {timeout} s; states seen {seen}')


def check_logins(host, port, user, password):
    c = Client(host, port)
    answer = c.post_json('/api/login', {'user': user, 'password': password + 'x'})
    expect_status(answer, 401, 'login with a wrong password')
    check(answer.error() == 'wrong user or password', f'wrong password: {answer.error()!r}')
    check(not c.session, 'a wrong password set a session cookie')
    answer = c.post_json('/api/login', {'user': 'nobody-here', 'password': password})
    expect_status(answer, 401, 'login of an unknown user')
    check(answer.error() == 'wrong user or password', f'unknown user: {answer.error()!r} (must not differ from a wrong password)')
    log('login: wrong password and unknown user -> 401 "wrong user or password"')

    # too many failures from one address: from 127.0.0.2 (also loopback), so 127.0.0.1 stays usable
    other = Client(host, port, source='127.0.0.2')
    statuses = []
    for _ in range(12):
        answer = other.post_json('/api/login', {'user': user, 'password': 'wrong'})
        statuses.append(answer.status)
        if answer.status == 429:
            break
    check(statuses[-1] == 429, f'no 429 after {len(statuses)} failed logins: {statuses}')
    check(statuses[0] == 401, f'the first failed login was not 401: {statuses}')
    check('retry in' in answer.error(), f'429 without "retry in N s": {answer.error()!r}')
    answer = other.post_json('/api/login', {'user': user, 'password': password})
    expect_status(answer, 429, 'the right password from a locked-out address')
    log(f'login: 127.0.0.2 locked out after {len(statuses) - 1} failures ({answer.error()}); the right password too')
    answer = Client(host, port).post_json('/api/login', {'user': user, 'password': 'wrong again'})
    expect_status(answer, 401, 'a failed login from 127.0.0.1 while 127.0.0.2 is locked out')

    answer = c.post_json('/api/login', {'user': user})
    expect_status(answer, 400, 'login without a password')
    answer = c.request('POST', '/api/login', body=json.dumps({'user': user, 'password': password}),
                       headers={'Content-Type': 'text/plain'})
    expect_status(answer, 415, 'login as text/plain')
    log('login: no password -> 400, text/plain -> 415')


def login(host, port, user, password):
    c = Client(host, port)
    answer = c.post_json('/api/login', {'user': user, 'password': password})
    expect_status(answer, 200, 'login with the right password')
    body = answer.json()
    check(body.get('user') == user and isinstance(body.get('expiresInS'), (int, float)) and body['expiresInS'] > 0,
          f'login answer {body}')
    cookie = answer.headers.get('set-cookie', '')
    check(c.session and len(c.session) >= 32, f'no vcu_session cookie: {cookie!r}')
    attributes = cookie.lower()
    for attribute in ('httponly', 'samesite=strict', 'path=/'):
        check(attribute in attributes, f'session cookie without {attribute}: {cookie!r}')
    info = c.get('/api/info').json()
    check(info['user'] == user, f'/api/info with the session: user {info["user"]!r}')
    log(f'login: 200 {body}, cookie {"; ".join(p.strip() for p in cookie.split(";")[1:])}')
    return c


def check_commands(host, port, c, anonymous):
    command = {'kind': 'operator', 'key': START_KEY, 'value': 'Start'}
    answer = anonymous.post_json('/api/command', command)
    expect_status(answer, 401, 'a command without a session')
    forged = Client(host, port)
    forged.session = '0' * 64
    expect_status(forged.post_json('/api/command', command), 401, 'a command with a made-up session')
    log('command: no session and a made-up session -> 401')

    state, _ = wait_state(c, lambda s: s == 'Standby', 'the FSM in Standby before Start')
    answer = c.post_json('/api/command', command)
    expect_status(answer, 200, 'operator Start')
    body = answer.json()
    check(body.get('accepted') is True and body.get('responder') == 'vcu-fsm', f'operator Start: {body}')
    state, seen = wait_state(c, lambda s: s != 'Standby', 'the FSM leaves Standby after Start', timeout=10)
    log(f'command: operator Start accepted by {body["responder"]}; live stream: {seen}')
    answer = c.post_json('/api/command', {'kind': 'operator', 'key': START_KEY, 'value': 0})
    expect_status(answer, 200, 'operator Stop')
    check(answer.json().get('accepted') is True, f'operator Stop: {answer.json()}')
    state, seen = wait_state(c, lambda s: s == 'Standby', 'the FSM back in Standby after Stop', timeout=30)
    log(f'command: operator Stop (value 0) accepted; live stream: {seen}')

    answer = c.post_json('/api/command', {'kind': 'set', 'key': FSM_KEY, 'value': 1})
    expect_status(answer, 200, f'set {FSM_KEY}')
    body = answer.json()
    check(body.get('accepted') is False and body.get('responder') == 'vcu-fsm' and body.get('reason'),
          f'set {FSM_KEY} should be refused by vcu-fsm with a reason: {body}')
    log(f'command: set {FSM_KEY} refused by {body["responder"]}: {body["reason"]}')

    bad = [
        ({'kind': 'set', 'key': 'no.such.Signal', 'value': 1}, 'no.such.Signal', 'an unknown key'),
        ({'kind': 'launch', 'key': START_KEY, 'value': 1}, None, 'an unknown kind'),
        ({'kind': 'set', 'key': START_KEY, 'value': {}}, '/value', 'a value that is an object'),
        ({'kind': 'operator', 'key': START_KEY, 'value': 'Sideways'}, None, 'an operator value text not in the table'),
        ({'key': START_KEY, 'value': 1}, '/kind', 'no kind'),
    ]
    # the other kinds reach their owners and come back decided (accepted or refused with a reason)
    message = 'HC1_Demands'
    others = [
        {'kind': 'scheduleEnable', 'key': message, 'value': 1},
        {'kind': 'scheduleCycle', 'key': message, 'value': 100},
        {'kind': 'clear', 'key': 'Vehicle_Control_Unit.HC1_Demands.ControlWord', 'value': 0},
    ]
    for command in others:
        answer = c.post_json('/api/command', command)
        expect_status(answer, 200, f'command {command}')
        body = answer.json()
        check(isinstance(body.get('accepted'), bool) and body.get('responder'), f'command {command}: {body}')
        check(body['accepted'] or body.get('reason'), f'command {command} refused without a reason: {body}')
        log(f'command {command["kind"]} {command["key"]}: {"accepted" if body["accepted"] else "refused"} by '
            f'{body["responder"]}{": " + body["reason"] if body.get("reason") else ""}')

    bad += [
        ({'kind': 'scheduleEnable', 'key': message, 'value': 2}, '/value', 'scheduleEnable 2'),
        ({'kind': 'scheduleEnable', 'key': 'NoSuchMessage', 'value': 1}, 'NoSuchMessage', 'an unknown message'),
    ]
    for command, named, what in bad:
        answer = c.post_json('/api/command', command)
        expect_status(answer, 400, f'command with {what}')
        error = answer.error()
        check(error.startswith('/'), f'command with {what}: the 400 names no JSON path: {error!r}')
        if named:
            check(named in error, f'command with {what}: the 400 does not name {named}: {error!r}')
        log(f'command with {what} -> 400 "{error}"')
    answer = c.post_json('/api/command', b'{"kind": "set", "key": ')
    expect_status(answer, 400, 'malformed JSON')
    check(answer.error().startswith('/'), f'malformed JSON: the 400 names no JSON path: {answer.error()!r}')
    log(f'command: malformed JSON -> 400 "{answer.error()}"')
    answer = c.post_json('/api/command', b'[1, 2]')
    expect_status(answer, 400, 'a JSON array body')
    check('/' in answer.error(), f'a JSON array body: the 400 names no JSON path: {answer.error()!r}')
    answer = c.request('POST', '/api/command', body=json.dumps(command), headers={'Content-Type': 'text/plain'})
    expect_status(answer, 415, 'a command as text/plain')
    status = announce_body(c, '/api/command', 'application/json', 70 * 1024)
    check(status == 413, f'a 70 KiB command body: HTTP {status}, expected 413')
    log('command: JSON array -> 400 with a path, text/plain -> 415, 70 KiB -> 413')
    check_same_origin(host, port, c)


def check_same_origin(host, port, c):
    """A POST is taken only from vcu-web's own origin: what another origin's page makes a browser
    send is refused naming the header, before anything reaches the stack."""
    command = json.dumps({'kind': 'operator', 'key': START_KEY, 'value': 'Start'})
    own = f'http://{host}:{port}'
    as_json = {'Content-Type': 'application/json'}
    refused = [
        ({**as_json, 'Origin': f'http://{host}:{port + 1}'}, 403, 'Origin', 'another port of the same host'),
        ({**as_json, 'Origin': 'null'}, 403, 'Origin', 'Origin null'),
        ({**as_json, 'Origin': f'https://{host}:{port}'}, 403, 'Origin', 'another scheme'),
        ({**as_json, 'Origin': own, 'Sec-Fetch-Site': 'same-site'}, 403, 'Sec-Fetch-Site', 'Sec-Fetch-Site same-site'),
        ({**as_json, 'Sec-Fetch-Site': 'cross-site'}, 403, 'Sec-Fetch-Site', 'Sec-Fetch-Site cross-site'),
        ({'Content-Type': 'text/plain; x=application/json', 'Origin': own}, 415, 'Content-Type', 'text/plain; x=application/json'),
        ({'Content-Type': 'multipart/form-data; boundary=application/json'}, 415, 'Content-Type', 'multipart, boundary=application/json'),
        ({'Content-Type': 'application/x-www-form-urlencoded; x=application/json'}, 415, 'Content-Type', 'urlencoded; x=application/json'),
    ]
    for headers, status, header, what in refused:
        answer = c.request('POST', '/api/command', body=command, headers=headers)
        expect_status(answer, status, f'a command with {what}')
        check(answer.error().startswith(header), f'a command with {what}: the {status} does not name {header}: {answer.error()!r}')
        log(f'command with {what} -> {status} "{answer.error()}"')
    for path in ('/api/login', '/api/logout'):
        answer = c.request('POST', path, body='{}', headers={**as_json, 'Origin': f'http://{host}:{port + 1}'})
        expect_status(answer, 403, f'{path} from another origin')
    answer = c.request('POST', '/api/uploads?name=cross.log', body=b'x',
                       headers={'Content-Type': 'application/octet-stream', 'Origin': f'http://{host}:{port + 1}'})
    expect_status(answer, 403, 'an upload from another origin')
    answer = c.request('POST', '/api/uploads?name=form.log', body=b'x', headers={'Content-Type': 'text/plain', 'Origin': own})
    expect_status(answer, 415, 'an upload as text/plain')
    check(not any(u['name'].startswith(('cross', 'form')) for u in c.get('/api/recordings').json()['uploads']),
          'a refused upload was kept')
    log('login, logout and uploads from another origin -> 403; an upload as text/plain -> 415, nothing kept')
    # the own origin (as the page sends it) still commands; the FSM stays the judge
    answer = c.request('POST', '/api/command', body=json.dumps({'kind': 'set', 'key': FSM_KEY, 'value': 1}),
                       headers={**as_json, 'Origin': own, 'Sec-Fetch-Site': 'same-origin'})
    expect_status(answer, 200, 'a command from the own origin')
    check(answer.json().get('responder') == 'vcu-fsm', f'a command from the own origin: {answer.json()}')
    log(f'command from the own origin {own} -> 200, decided by vcu-fsm')


def check_fault_reset(c):
    """faultReset (key empty: every latched fault) is decided by the stack like the HMI's Reset."""
    answer = c.post_json('/api/command', {'kind': 'faultReset', 'key': '', 'value': 1})
    expect_status(answer, 200, 'faultReset')
    body = answer.json()
    check(isinstance(body.get('accepted'), bool) and body.get('responder'), f'faultReset: {body}')
    log(f'command faultReset: {"accepted" if body["accepted"] else "refused"} by {body["responder"]}'
        f'{": " + body["reason"] if body.get("reason") else ""}')


def check_traversal(c, recording):
    attempts = [
        '/../../etc/passwd',
        '/%2e%2e/%2e%2e/etc/passwd',
        '/..%2f..%2f..%2fetc%2fpasswd',
        '/%2e%2e%2f%2e%2e%2f%2e%2e%2fetc%2fpasswd',
        '/www/../../../../etc/passwd',
        '/..\\..\\etc\\passwd',
        '/%00/etc/passwd',
        '//etc/passwd',
        '/api/recordings/..%2Fetc/archive',
        '/api/recordings/..%2F..%2F..%2Fetc/archive',
        '/api/recordings/../../etc/passwd/archive',
        '/api/recordings/%2e%2e/report',
        '/api/recordings/escape/archive',
        '/api/recordings/escape/summary',
        '/api/uploads/..%2F..%2F..%2Fetc%2Fpasswd/report',
        '/api/uploads/%2Fetc%2Fpasswd/summary',
        f'/api/recordings/{recording}%2F..%2F..%2F..%2Fetc/archive',
    ]
    for path in attempts:
        answer = c.get(path)
        check(answer.status in (400, 403, 404), f'GET {path}: expected 400/403/404, got {answer!r}')
        check(PASSWD_LINE.encode() not in answer.body, f'GET {path} served /etc/passwd')
        check(not answer.body.startswith(b'\x1f\x8b'), f'GET {path} served an archive')
    log(f'traversal: {len(attempts)} paths (.., %2e%2e, %2f, backslash, NUL, a symlink out of recordings/) -> 400/403/404')


def check_recordings(c, recording):
    answer = c.get('/api/recordings')
    expect_status(answer, 200, 'GET /api/recordings')
    listing = answer.json()
    check(isinstance(listing.get('recordings'), list) and isinstance(listing.get('uploads'), list), f'recordings: {listing}')
    entry = next((r for r in listing['recordings'] if r.get('name') == recording), None)
    check(entry is not None, f'recording {recording} not listed: {listing}')
    check(set(entry) >= {'name', 'bytes', 'modifiedUnixMs', 'files'}, f'recording entry {entry}')
    files = {f['name']: f['bytes'] for f in entry['files']}
    check('vehicle.log' in files and files['vehicle.log'] > 0, f'recording {recording} files {files}')
    check(entry['bytes'] == sum(files.values()), f'recording bytes {entry["bytes"]} != sum of files {files}')
    now_ms = time.time() * 1000
    check(abs(now_ms - entry['modifiedUnixMs']) < 3600 * 1000, f'modifiedUnixMs {entry["modifiedUnixMs"]} vs now {now_ms:.0f}')
    log(f'recordings: {recording} {files}')

    answer = c.get(f'/api/recordings/{recording}/archive', timeout=60)
    expect_status(answer, 200, 'the archive')
    check(answer.headers.get('content-type', '').startswith('application/gzip'), f'archive type {answer.headers.get("content-type")}')
    disposition = answer.headers.get('content-disposition', '')
    check('attachment' in disposition and f'{recording}.tar.gz' in disposition, f'archive Content-Disposition {disposition!r}')
    with tarfile.open(fileobj=io.BytesIO(answer.body), mode='r:gz') as archive:
        members = {m.name: m for m in archive.getmembers()}
        for name, size in files.items():
            member = members.get(f'{recording}/{name}')
            check(member is not None and member.isfile(), f'archive lacks {recording}/{name}: {list(members)}')
            check(member.size == size, f'archive {name}: {member.size} bytes, listed {size}')
        for name in members:
            check(name == recording or name.startswith(f'{recording}/'), f'archive member outside {recording}/: {name}')
            check('..' not in name.split('/'), f'archive member with ..: {name}')
        log_bytes = archive.extractfile(members[f'{recording}/vehicle.log']).read()
    check(b' vehicle ' in log_bytes[:4096], f'vehicle.log in the archive is not candump -L of bus vehicle: {log_bytes[:200]!r}')
    log(f'archive: {len(answer.body)} bytes of gzip tar, members {sorted(members)}')

    answer = c.get(f'/api/recordings/{recording}/summary', timeout=60)
    expect_status(answer, 200, 'recording summary')
    summary = answer.json()
    check(set(summary) >= {'frames', 'durationS', 'buses', 'findings'}, f'summary {summary}')
    check(summary['frames'] > 100 and 1.0 < summary['durationS'] < 10, f'summary of a 3 s recording: {summary}')
    check(set(summary['findings']) >= {'errors', 'warnings'}, f'summary findings {summary["findings"]}')
    log(f'recording summary: {summary}')
    answer = c.get(f'/api/recordings/{recording}/report', timeout=60)
    expect_status(answer, 200, 'recording report')
    check(answer.headers.get('content-type', '').startswith('text/html'), f'report type {answer.headers.get("content-type")}')
    check(b'<html' in answer.body[:2000].lower() and len(answer.body) > 2000, f'report: {answer.body[:200]!r}')
    log(f'recording report: {len(answer.body)} bytes of HTML')
    for path in ('/api/recordings/no-such-recording/archive', '/api/recordings/no-such-recording/report',
                 '/api/uploads/no-such-upload/summary'):
        expect_status(c.get(path), 404, f'GET {path}')
    log('recordings: a missing recording or upload -> 404')


def check_uploads(host, port, c, anonymous, log_path):
    with open(log_path, 'rb') as file:
        content = file.read()
    answer = anonymous.request('POST', '/api/uploads?name=anonymous.log', body=content,
                               headers={'Content-Type': 'application/octet-stream'})
    expect_status(answer, 401, 'an upload without a session')
    answer = c.request('POST', '/api/uploads?name=' + urllib.parse.quote('../../evil name.log'), body=content,
                       headers={'Content-Type': 'application/octet-stream'})
    expect_status(answer, 200, 'an upload')
    name = answer.json().get('name')
    check(isinstance(name, str) and name and '/' not in name and not name.startswith('.'), f'upload name {name!r}')
    log(f'upload: "../../evil name.log" kept as {name!r}')
    listing = c.get('/api/recordings').json()
    entry = next((u for u in listing['uploads'] if u.get('name') == name), None)
    check(entry is not None and entry['bytes'] == len(content), f'upload {name} not listed with {len(content)} bytes: {listing["uploads"]}')
    answer = c.get(f'/api/uploads/{urllib.parse.quote(name)}/summary', timeout=60)
    expect_status(answer, 200, 'upload summary')
    summary = answer.json()
    check(summary.get('frames', 0) > 0, f'upload summary: {summary}')
    answer = c.get(f'/api/uploads/{urllib.parse.quote(name)}/report', timeout=60)
    expect_status(answer, 200, 'upload report')
    check(answer.headers.get('content-type', '').startswith('text/html') and b'<html' in answer.body[:2000].lower(),
          f'upload report: {answer!r}')
    log(f'upload: summary {summary}, report {len(answer.body)} bytes')

    # Oversized: a Content-Length past any limit; vcu-web must refuse on the header, before any
    # byte of the body.
    before = {u['name'] for u in c.get('/api/recordings').json()['uploads']}
    status = announce_body(c, '/api/uploads?name=huge.log', 'application/octet-stream', 1 << 40)
    check(status == 413, f'oversized upload: HTTP {status}, expected 413')
    # the 413 came before any byte was read: an upload is listed only once accepted whole
    after = {u['name'] for u in c.get('/api/recordings').json()['uploads']}
    check(after == before, f'an oversized upload left something: {after - before}')
    log(f'upload: 1 TiB announced -> {status}, nothing kept')


def check_logout(host, port, c):
    token = c.session
    answer = c.post_json('/api/logout', {})
    expect_status(answer, 200, 'logout')
    cookie = answer.headers.get('set-cookie', '')
    check(cookie.startswith('vcu_session=') and ('max-age=0' in cookie.lower() or 'expires=' in cookie.lower()),
          f'logout does not clear the cookie: {cookie!r}')
    old = Client(host, port)
    old.session = token
    expect_status(old.post_json('/api/command', {'kind': 'operator', 'key': START_KEY, 'value': 'Start'}), 401,
                  'a command with the logged-out session')
    check(old.get('/api/info').json()['user'] is None, '/api/info names a user for a logged-out session')
    expect_status(Client(host, port).post_json('/api/logout', {}), 401, 'logout without a session')
    log(f'logout: 200, cookie cleared ({cookie.split(";")[0]}...), the old session is refused')


def check_read_only(c, missing_users_file):
    """vcu-web whose users file does not exist: the pages are read-only, logins 503 with the reason."""
    answer = c.get('/api/info')
    expect_status(answer, 200, 'GET /api/info (read-only)')
    check(answer.json().get('loginAvailable') is False, f'read-only: loginAvailable {answer.json()}')
    answer = c.post_json('/api/login', {'user': 'alice', 'password': 'whatever'})
    expect_status(answer, 503, 'login without a users file')
    check(os.path.basename(missing_users_file) in answer.error(), f'the 503 does not name the users file: {answer.error()!r}')
    expect_status(c.post_json('/api/command', {'kind': 'operator', 'key': START_KEY, 'value': 1}), 401,
                  'a command to a read-only vcu-web')
    expect_status(c.get('/'), 200, 'the page of a read-only vcu-web')
    stream = LiveStream(c, [FSM_KEY])
    try:
        check(stream.status == 200, f'/api/live of a read-only vcu-web: HTTP {stream.status}')
        state = stream.next_update(10)['header']['state']
    finally:
        stream.close()
    log(f'read-only: loginAvailable false, login -> 503 "{answer.error()}", command -> 401, live view works ({state})')


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--url', required=True, help='http://127.0.0.1:PORT')
    parser.add_argument('--user')
    parser.add_argument('--recording', help='a recording in the data folder (vcu record)')
    parser.add_argument('--log', help='a small candump -L file to upload')
    parser.add_argument('--read-only', metavar='MISSING_USERS_FILE',
                        help='only the checks of a vcu-web started with this (missing) users file')
    args = parser.parse_args()
    url = urllib.parse.urlsplit(args.url)
    if args.read_only:
        try:
            check_read_only(Client(url.hostname, url.port), args.read_only)
        except (Failure, OSError, http.client.HTTPException) as failure:
            print(f'{NAME}: FAIL (read-only): {failure}', flush=True)
            return 1
        print(f'{NAME}: PASS (read-only)', flush=True)
        return 0
    if not (args.user and args.recording and args.log):
        parser.error('--user, --recording and --log are needed (or --read-only)')
    password = os.environ.get('OPENVCU_WEB_PASSWORD', '')
    if not password:
        print(f'{NAME}: FAIL: OPENVCU_WEB_PASSWORD is not set')
        return 1
    host, port = url.hostname, url.port
    anonymous = Client(host, port)
    failures = []

    def run(what, check_function, *arguments):
        """One group of checks; a failure is reported and the next group still runs."""
        try:
            return check_function(*arguments)
        except Failure as failure:
            text = str(failure)
        except (OSError, http.client.HTTPException) as error:
            text = f'{type(error).__name__}: {error}'
        print(f'{NAME}: FAIL ({what}): {text}', flush=True)
        failures.append(f'{what}: {text}')
        return None

    run('static', check_static, anonymous)
    info = run('info', check_info, anonymous)
    catalog = run('catalog', check_catalog, anonymous)
    if info and catalog:
        run('live', check_live, anonymous, info, catalog)
    run('logins', check_logins, host, port, args.user, password)
    c = run('login', login, host, port, args.user, password)
    if c:
        run('commands', check_commands, host, port, c, anonymous)
        run('fault reset', check_fault_reset, c)
        run('traversal', check_traversal, c, args.recording)
        run('recordings', check_recordings, c, args.recording)
        run('uploads', check_uploads, host, port, c, anonymous, args.log)
        run('logout', check_logout, host, port, c)
    if failures:
        print(f'{NAME}: FAIL: {len(failures)} group(s): ' + '; '.join(f.split(':')[0] for f in failures), flush=True)
        return 1
    print(f'{NAME}: PASS', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())

#!/usr/bin/python3
"""A page of another origin cannot make a logged-in operator's browser command the VCU
(docs/design/web.md, "Same-origin requests"). Real headless chromium against vcu-web on the
simulated HHEA stack (web_stack_test.sh cross-origin starts it), the FSM in Standby:

  1. the operator logs in on vcu-web's own page (http://127.0.0.1:PORT);
  2. the same browser opens an attacker's page served by this script from a second origin,
     another port of 127.0.0.1 (same site: the SameSite=Strict cookie is sent). The page tries
     Start on the operator switch by every request a page can send without a CORS preflight:
     fetch with mode no-cors and Content-Type "text/plain; x=application/json",
     "application/x-www-form-urlencoded; x=application/json", "multipart/form-data;
     boundary=application/json" and a FormData body; a fetch with mode cors and
     application/json (needs a preflight); plain HTML forms (text/plain, urlencoded,
     multipart) posted into frames; uploads by a fetch and by a multipart form; then a logout
     by fetch and by a form, and a top-level form navigation to /api/command;
  3. vcu-fsm accepted none: no line was added to vcu-web's command log (every command sent
     to the stack is logged there), the FSM is still in Standby with the switch off, no
     upload was stored, the session is still logged in, and the navigation shows vcu-web's
     403 naming the header (Sec-Fetch-Site, checked first, or Origin);
  4. vcu-web's own page still commands: Start accepted by vcu-fsm, then Stop.

  web_cross_origin_test.py --url http://127.0.0.1:PORT --user alice --attacker-port PORT2
                           --command-log DATA/web-commands.log --web-log FILE
  (the password in the environment: OPENVCU_WEB_PASSWORD)

Exit 0 PASS, 1 FAIL, 77 when chromium, chromium-driver or python3-selenium is missing.
"""

import argparse
import http.server
import json
import os
import sys
import threading
import time
import urllib.parse

from web_browser_test import CHROMEDRIVER, CHROMIUM, SKIP, START_KEY, Failure, Page, open_browser

NAME = 'web_cross_origin_test'
COMMAND = {'kind': 'operator', 'key': START_KEY, 'value': 'Start'}

try:
    from selenium import webdriver
    from selenium.common.exceptions import WebDriverException
    from selenium.webdriver.common.by import By
except ImportError as error:
    webdriver = None
    IMPORT_ERROR = str(error)


def log(text):
    print(f'{NAME}: {text}', flush=True)


def attack_page(target):
    """The attacker's page: every request a page of another origin can make the browser send.
    Sets document.title to 'done' and window.attackResults to what each try did."""
    body = json.dumps(COMMAND)
    # a text/plain form sends "NAME=VALUE": the name carries the JSON, the value closes it
    form_name = body[:-1] + ',"pad":"'
    return f"""<!doctype html><meta charset="utf-8"><title>attacker</title>
<body>
<iframe name="sink1"></iframe><iframe name="sink2"></iframe><iframe name="sink3"></iframe>
<iframe name="sink4"></iframe><iframe name="sink5"></iframe>
<form id="form-text" method="post" action="{target}/api/command" enctype="text/plain" target="sink1">
  <input type="hidden" name='{form_name}' value='"}}'></form>
<form id="form-urlencoded" method="post" action="{target}/api/command" target="sink2">
  <input type="hidden" name="kind" value="operator"><input type="hidden" name="key" value="{START_KEY}">
  <input type="hidden" name="value" value="Start"></form>
<form id="form-multipart" method="post" action="{target}/api/command" enctype="multipart/form-data" target="sink3">
  <input type="hidden" name="json" value='{body}'></form>
<form id="form-upload" method="post" action="{target}/api/uploads?name=csrf-form.log" enctype="multipart/form-data"
      target="sink4"><textarea name="file">(000.000000) can0 18FF0121#0102030405060708</textarea></form>
<form id="form-logout" method="post" action="{target}/api/logout" target="sink5"></form>
<script>
const target = {json.dumps(target)};
const body = {json.dumps(body)};
const results = {{}};
window.attackResults = results;
async function send(name, path, init) {{
  try {{
    const response = await fetch(target + path, Object.assign({{method: 'POST', credentials: 'include'}}, init));
    results[name] = 'sent (' + response.type + ')';
  }} catch (e) {{
    results[name] = 'not sent: ' + e;
  }}
}}
function submitInto(form, frame) {{
  return new Promise((resolve) => {{
    const sink = document.querySelector('iframe[name="' + frame + '"]');
    const timer = setTimeout(() => {{ results[form] = 'submitted (no load event)'; resolve(); }}, 3000);
    sink.addEventListener('load', () => {{ clearTimeout(timer); results[form] = 'submitted'; resolve(); }}, {{once: true}});
    document.getElementById(form).submit();
  }});
}}
async function attack() {{
  const multipart = new FormData();
  multipart.append('json', body);
  await Promise.all([
    send('fetch text/plain; x=application/json', '/api/command',
         {{mode: 'no-cors', headers: {{'Content-Type': 'text/plain; x=application/json'}}, body}}),
    send('fetch urlencoded; x=application/json', '/api/command',
         {{mode: 'no-cors', headers: {{'Content-Type': 'application/x-www-form-urlencoded; x=application/json'}}, body}}),
    send('fetch multipart; boundary=application/json', '/api/command',
         {{mode: 'no-cors', headers: {{'Content-Type': 'multipart/form-data; boundary=application/json'}}, body}}),
    send('fetch FormData', '/api/command', {{mode: 'no-cors', body: multipart}}),
    send('fetch text/plain (no type given)', '/api/command', {{mode: 'no-cors', body}}),
    send('fetch cors application/json', '/api/command',
         {{mode: 'cors', headers: {{'Content-Type': 'application/json'}}, body}}),
    send('fetch upload text/plain', '/api/uploads?name=csrf-fetch.log',
         {{mode: 'no-cors', headers: {{'Content-Type': 'text/plain'}}, body: '(0.0) can0 123#00'}}),
    submitInto('form-text', 'sink1'),
    submitInto('form-urlencoded', 'sink2'),
    submitInto('form-multipart', 'sink3'),
    submitInto('form-upload', 'sink4'),
  ]);
  // the logout last: a logout that worked would hide whether the commands did
  await send('fetch logout', '/api/logout', {{mode: 'no-cors'}});
  await submitInto('form-logout', 'sink5');
  document.title = 'done';
}}
attack();
</script>"""


def navigation_page(target):
    """A top-level form navigation POST (no frame): the browser shows vcu-web's answer."""
    body = json.dumps(COMMAND)
    form_name = body[:-1] + ',"pad":"'
    return f"""<!doctype html><meta charset="utf-8"><title>navigate</title>
<form id="nav" method="post" action="{target}/api/command" enctype="text/plain">
  <input type="hidden" name='{form_name}' value='"}}'></form>
<script>document.getElementById('nav').submit();</script>"""


def serve_attacker(port, target):
    pages = {'/attack.html': attack_page(target), '/navigate.html': navigation_page(target)}

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            page = pages.get(urllib.parse.urlsplit(self.path).path)
            data = (page or 'not found').encode()
            self.send_response(200 if page else 404)
            self.send_header('Content-Type', 'text/html; charset=utf-8')
            self.send_header('Content-Length', str(len(data)))
            self.end_headers()
            self.wfile.write(data)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(('127.0.0.1', port), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def lines_of(path):
    try:
        with open(path, encoding='utf-8', errors='replace') as file:
            return file.read().splitlines()
    except FileNotFoundError:
        return []


def page_fetch_json(page, path):
    """GET `path` from the page's own origin (with its cookie): [status, body]."""
    return page.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "fetch(arguments[0], {credentials: 'same-origin'}).then(async (r) => done([r.status, await r.json()]))"
        ".catch((e) => done([0, String(e)]));", path)


def login(page, url, user, password):
    page.driver.get(url)
    page.wait(lambda: page.text('#connection') == 'connected', 'the page connects to /api/live')
    page.type('#login-user', user)
    page.type('#login-password', password)
    page.click('#login-button')
    page.wait(lambda: page.text('#whoami') == user, '#whoami after the login')
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'the FSM in Standby', timeout=30)
    start = f'#operator button[data-key="{START_KEY}"]'
    page.wait(lambda: page.find(start).is_enabled() and page.find(start).get_attribute('data-on') == 'false',
              'the Start/Stop switch enabled and off')
    log(f'same origin: logged in as "{page.text("#whoami")}" on {url}, FSM "{page.text("#fsm-state")}"')


def check_attack(page, url, attacker, user, command_log, web_log):
    commands_before = len(lines_of(command_log))
    web_log_before = len(lines_of(web_log))
    started = time.monotonic()
    page.driver.get(f'{attacker}/attack.html')
    page.wait(lambda: page.driver.title == 'done', 'the attacker page sent everything', timeout=20)
    results = page.driver.execute_script('return window.attackResults;')
    log(f'attacker {attacker}: {len(results)} tries in {time.monotonic() - started:.1f} s')
    for name, outcome in sorted(results.items()):
        log(f'  {name}: {outcome}')
    sent = [name for name, outcome in results.items() if outcome.startswith('sent') or outcome.startswith('submitted')]
    if len(sent) < len(results) - 1:  # only the cors fetch may be stopped by the browser itself
        raise Failure(f'the browser did not send the tries (the test would prove nothing): {results}')
    # the navigation POST: the browser shows vcu-web's own answer
    page.driver.get(f'{attacker}/navigate.html')
    page.wait(lambda: page.driver.current_url.startswith(url), 'the form navigation reaches vcu-web')
    answer = page.wait(lambda: page.find('body').text.strip(), 'the answer of the navigation POST')
    log(f'navigation POST to {url}api/command: {answer}')

    # nothing reached the stack, nothing changed
    added = lines_of(command_log)[commands_before:]
    page.driver.get(url)
    page.wait(lambda: page.text('#connection') == 'connected', 'the page connects again')
    page.wait(lambda: page.text('#fsm-state') not in ('', '…'), 'an FSM state')
    state = page.text('#fsm-state')
    start = f'#operator button[data-key="{START_KEY}"]'
    switch_on = page.wait(lambda: page.find(start).get_attribute('data-on'), 'the switch state')
    status, listing = page_fetch_json(page, '/api/recordings')
    uploads = [u.get('name') for u in listing.get('uploads', [])] if status == 200 else None
    status, info = page_fetch_json(page, '/api/info')
    refusals = [line for line in lines_of(web_log)[web_log_before:] if 'refused ' in line and ' from ' in line]
    log(f'after the attack: {len(added)} command(s) reached the stack {added}; FSM "{state}", switch on: {switch_on}; '
        f'uploads {uploads}; /api/info user {info.get("user") if isinstance(info, dict) else info!r}')
    log(f'vcu-web logged {len(refusals)} refusal(s), e.g. {refusals[0].strip() if refusals else "-"}')
    problems = []
    if added:
        problems.append(f'{len(added)} command(s) from the other origin reached the stack: {added}')
    if state != 'Standby' or switch_on != 'false':
        problems.append(f'the FSM is in "{state}" and the switch on={switch_on} (expected Standby, off)')
    if uploads is None or any(name.startswith('csrf') for name in uploads):
        problems.append(f'an upload from the other origin was stored: {uploads}')
    if not isinstance(info, dict) or info.get('user') != user:
        problems.append(f'the other origin logged the operator out: /api/info {info}')
    if '"error"' not in answer or not ('Sec-Fetch-Site' in answer or 'Origin' in answer):
        problems.append(f'the navigation POST was not refused naming the Sec-Fetch-Site or Origin header: {answer}')
    if problems:
        raise Failure('; '.join(problems))


def check_same_origin(page):
    start = f'#operator button[data-key="{START_KEY}"]'
    page.wait(lambda: page.find(start).is_enabled(), 'the switch enabled on vcu-web\'s own page')
    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm', 'Start from the own page accepted by vcu-fsm')
    page.wait(lambda: page.text('#fsm-state') != 'Standby', 'the FSM leaves Standby after Start')
    log(f'same origin: Start -> "{page.text("#command-result")}", FSM "{page.text("#fsm-state")}"')
    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm' and
              page.find(start).get_attribute('data-on') == 'false', 'Stop accepted')
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'Standby after Stop', timeout=30)
    log('same origin: Stop accepted, FSM back in Standby')


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--url', required=True)
    parser.add_argument('--user', required=True)
    parser.add_argument('--attacker-port', type=int, required=True)
    parser.add_argument('--command-log', required=True, help="vcu-web's <data folder>/web-commands.log")
    parser.add_argument('--web-log', required=True, help="vcu-web's output")
    parser.add_argument('--screenshots', default=os.environ.get('OPENVCU_WEB_SCREENSHOTS', '.'))
    args = parser.parse_args()
    if webdriver is None:
        print(f'{NAME}: SKIPPED: python3-selenium is missing ({IMPORT_ERROR})')
        return SKIP
    for program in (CHROMIUM, CHROMEDRIVER):
        if not (os.path.isfile(program) and os.access(program, os.X_OK)):
            print(f'{NAME}: SKIPPED: {program} is missing (Debian packages chromium, chromium-driver)')
            return SKIP
    password = os.environ.get('OPENVCU_WEB_PASSWORD', '')
    if not password:
        print(f'{NAME}: FAIL: OPENVCU_WEB_PASSWORD is not set')
        return 1
    url = args.url if args.url.endswith('/') else args.url + '/'
    target = url.rstrip('/')
    attacker_server = serve_attacker(args.attacker_port, target)
    attacker = f'http://127.0.0.1:{args.attacker_port}'
    os.makedirs(args.screenshots, exist_ok=True)
    try:
        driver = open_browser()
    except WebDriverException as error:
        print(f'{NAME}: FAIL: chromium did not start: {error.msg}')
        return 1
    page = Page(driver, args.screenshots)
    status = 0
    try:
        login(page, url, args.user, password)
        check_attack(page, url, attacker, args.user, args.command_log, args.web_log)
        check_same_origin(page)
        print(f'{NAME}: PASS', flush=True)
    except (Failure, WebDriverException) as failure:
        text = failure.msg if isinstance(failure, WebDriverException) else str(failure)
        print(f'{NAME}: FAIL: {text}', flush=True)
        try:
            driver.save_screenshot(os.path.join(args.screenshots, 'cross-origin-failure.png'))
        except WebDriverException:
            pass
        status = 1
    finally:
        driver.quit()
        attacker_server.shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())

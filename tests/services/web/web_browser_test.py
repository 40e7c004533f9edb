#!/usr/bin/python3
"""vcu-web's page in a real browser (Debian's chromium, headless, driven by python3-selenium
through chromium-driver), against the running stack (web_stack_test.sh starts it):

  1. the live page shows the FSM state and the connection, signals picked in the tree get
     values and the plot draws them;
  2. after a login, Start on the operator switch is accepted by vcu-fsm, the FSM state in the
     header changes and the woken battery's signal shows its value-table text; a refused
     command shows vcu-fsm's reason; a cycle change is accepted by vcu-can-tx; after Stop the
     battery's signal goes stale;
  3. the recording's summary, download and report; a log uploaded from the page is analysed
     and its report shown; logout disables the commands again;
  4. vcu-web killed (--kill-command) while the page is open: the page shows "reconnecting";
     started again (--start-command): the page is connected again by itself, updates flow,
     the lost session shows as logged out, and a new login commands the VCU again;
  5. a battery fault injected in Ready (--fault-on-command): the FSM's fault and the VIC's DM1
     DTC are listed; cleared (--fault-off-command) and reset from the page, Stop gets Standby.

  web_browser_test.py --url http://127.0.0.1:PORT --user alice --log FILE
                      --screenshots DIR --kill-command CMD --start-command CMD
                      --fault-on-command CMD --fault-off-command CMD
  (the password in the environment: OPENVCU_WEB_PASSWORD)

Exit 0 PASS, 1 FAIL, 77 when chromium, chromium-driver or python3-selenium is missing.
Screenshots (01-live.png ...) go to DIR, also on failure (failure.png).
"""

import argparse
import os
import shlex
import subprocess
import sys
import time

NAME = 'web_browser_test'
CHROMIUM = '/usr/bin/chromium'
CHROMEDRIVER = '/usr/bin/chromedriver'
START_KEY = 'internal.operator.StartStop'
FSM_KEY = 'internal.fsm.state'
SKIP = 77

try:
    from selenium import webdriver
    from selenium.common.exceptions import TimeoutException, WebDriverException
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait
except ImportError as error:  # checked in main(): a skip, never a pass
    webdriver = None
    IMPORT_ERROR = str(error)


class Failure(Exception):
    pass


def log(text):
    print(f'{NAME}: {text}', flush=True)


class Page:
    def __init__(self, driver, screenshots):
        self.driver = driver
        self.screenshots = screenshots
        self.shots = 0

    def find(self, css):
        return self.driver.find_element(By.CSS_SELECTOR, css)

    def text(self, css):
        return self.find(css).text

    def wait(self, condition, what, timeout=15):
        """Polls condition() (exceptions count as "not yet") until truthy; returns its value."""
        last = [None]

        def attempt(_driver):
            try:
                return condition()
            except WebDriverException as error:
                last[0] = error
                return False
        try:
            return WebDriverWait(self.driver, timeout, poll_frequency=0.1).until(attempt)
        except TimeoutException:
            detail = f' (last error: {last[0].msg if hasattr(last[0], "msg") else last[0]})' if last[0] else ''
            raise Failure(f'{what}: not within {timeout} s{detail}; #connection "{self.safe_text("#connection")}", '
                          f'#fsm-state "{self.safe_text("#fsm-state")}", #command-result "{self.safe_text("#command-result")}"')

    def safe_text(self, css):
        try:
            return self.text(css)
        except WebDriverException:
            return '?'

    def screenshot(self, name):
        self.shots += 1
        path = os.path.join(self.screenshots, f'{self.shots:02d}-{name}.png')
        self.driver.save_screenshot(path)
        log(f'screenshot {path}')

    def click(self, css):
        self.find(css).click()

    def type(self, css, text):
        field = self.find(css)
        field.clear()
        field.send_keys(text)

    def updates(self):
        """How many update events the page has received (#connection data-updates)."""
        return int(self.find('#connection').get_attribute('data-updates') or 0)


def open_browser():
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for argument in ('--headless=new', '--no-sandbox', '--disable-gpu', '--window-size=1280,900',
                     '--disable-dev-shm-usage', '--no-first-run', '--disable-extensions',
                     '--disable-background-networking', '--disable-component-update'):
        options.add_argument(argument)
    options.set_capability('goog:loggingPrefs', {'browser': 'ALL'})
    service = Service(executable_path=CHROMEDRIVER)
    return webdriver.Chrome(service=service, options=options)


def check_live(page, url):
    page.driver.get(url)
    page.wait(lambda: page.text('#connection') == 'connected', 'the page connects to /api/live')
    state = page.wait(lambda: page.text('#fsm-state') not in ('', '…') and page.text('#fsm-state'), 'an FSM state in #fsm-state')
    page.wait(lambda: page.text('#fsm-since').startswith('for '), '#fsm-since')
    page.wait(lambda: page.text('#health') not in ('', '…'), '#health')
    page.wait(lambda: page.driver.find_elements(By.CSS_SELECTOR, '#services .chip'), 'the services in the header')
    log(f'live: FSM "{state}" {page.text("#fsm-since")}, SOC "{page.text("#soc")}", health "{page.text("#health")}", '
        f'services {[c.text for c in page.driver.find_elements(By.CSS_SELECTOR, "#services .chip")]}')

    # pick the FSM state and a received signal through the tree's search
    rx_key = page.driver.execute_script(
        "const leaf = document.querySelector('#signal-tree li.leaf .badge.rx'); return leaf && leaf.parentElement.dataset.key;")
    if not rx_key:
        raise Failure('no received signal in #signal-tree')
    for key in (FSM_KEY, rx_key):
        page.type('#signal-search', key)
        leaf = f'#signal-tree li.leaf[data-key="{key}"]'
        page.wait(lambda: 'match' in page.text('#catalog-status') and page.find(leaf).is_displayed(), f'{key} shown by the search')
        page.wait(lambda: page.click(leaf) or True, f'a click on {key} in the tree')
        page.wait(lambda: page.driver.find_elements(By.CSS_SELECTOR, f'#picked tr[data-key="{key}"]'), f'{key} in #picked')
    page.type('#signal-search', '')
    row = f'#picked tr[data-key="{FSM_KEY}"]'
    page.wait(lambda: page.find(row + ' td.value').text not in ('', '—') and
              page.find(row + ' td.status').get_attribute('data-status') == 'Ready', f'{FSM_KEY} has a Ready value')
    page.wait(lambda: page.find(f'#picked tr[data-key="{rx_key}"] td.status').text not in ('', 'waiting'),
              f'{rx_key} has a status')
    legend = page.wait(lambda: [li.get_attribute('data-key') for li in page.driver.find_elements(By.CSS_SELECTOR, '#plot-legend li[data-key]')],
                       'the plot legend')
    if legend[:2] != [FSM_KEY, rx_key]:
        raise Failure(f'plot legend {legend}, expected [{FSM_KEY}, {rx_key}]')
    # the first lane's colour (#4fc3f7, light blue; antialiased a darker blue) right of the
    # axis labels (which are drawn in the lane's colour too): the FSM state's line is drawn
    count_pixels = """
      const c = document.getElementById('plot'); const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const left = Math.ceil(66 * (window.devicePixelRatio || 1));
      let n = 0;
      for (let y = 0; y < c.height; ++y) for (let x = left; x < c.width; ++x) {
        const i = 4 * (y * c.width + x);
        if (d[i + 2] > 100 && d[i + 2] - d[i] > 60 && d[i + 1] > 80) n++;
      }
      return n;"""
    pixels = page.wait(lambda: page.driver.execute_script(count_pixels) > 50 and page.driver.execute_script(count_pixels),
                       'the plot draws the FSM state', timeout=10)
    rx_row = f'#picked tr[data-key="{rx_key}"]'
    log(f'live: picked {FSM_KEY} = "{page.find(row + " td.value").text}" and {rx_key} = '
        f'"{page.find(rx_row + " td.value").text}" ({page.find(rx_row + " td.status").text}); '
        f'plot legend {legend}, {pixels} pixels of lane 1')
    page.screenshot('live')
    return rx_key


def check_commands(page, user, password, rx_key):
    start = f'#operator button[data-key="{START_KEY}"]'
    page.wait(lambda: page.find(start), 'the Start/Stop operator switch')
    if page.find(start).is_enabled() or page.find('#set-button').is_enabled():
        raise Failure('commands are enabled before a login')
    page.type('#login-user', user)
    page.type('#login-password', password + '-wrong')
    page.click('#login-button')
    page.wait(lambda: page.text('#login-error') != '', 'a wrong password is reported')
    log(f'login: wrong password -> "{page.text("#login-error")}"')
    page.type('#login-user', user)
    page.type('#login-password', password)
    page.click('#login-button')
    page.wait(lambda: page.text('#whoami') == user, '#whoami after the login')
    page.wait(lambda: page.find(start).is_enabled(), 'the operator switch enabled after the login')
    log(f'login: #whoami "{page.text("#whoami")}"')

    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'the FSM in Standby before Start', timeout=30)
    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm', 'Start accepted by vcu-fsm')
    page.wait(lambda: page.text('#fsm-state') != 'Standby', 'the FSM state changes after Start')
    after = page.text('#fsm-state')
    page.wait(lambda: page.find(start).get_attribute('data-on') == 'true', 'the switch shows Start')
    log(f'command: Start -> "{page.text("#command-result")}", FSM "{after}", switch "{" ".join(page.text(start).split())}"')
    # the woken battery (VIC) sends: its picked signal becomes Ready with its value-table text
    rx_row = f'#picked tr[data-key="{rx_key}"]'
    page.wait(lambda: page.find(rx_row + ' td.status').get_attribute('data-status') == 'Ready', f'{rx_key} Ready after Start')
    rx_text, rx_raw = page.text(rx_row + ' td.value'), page.text(rx_row + ' td.raw')
    values = page.driver.execute_script(
        "return fetch('/api/catalog').then((r) => r.json()).then((c) => c.signals.find((s) => s.key === arguments[0]).values);", rx_key)
    if values and rx_raw and values.get(rx_raw) != rx_text:
        raise Failure(f'{rx_key} shows "{rx_text}" for raw {rx_raw}; its value table says {values.get(rx_raw)!r}')
    log(f'live: {rx_key} Ready: "{rx_text}" (raw {rx_raw or "-"})')
    page.screenshot('started')

    page.type('#set-key', FSM_KEY)
    page.type('#set-value', '1')
    page.click('#set-button')
    page.wait(lambda: page.text('#command-result').startswith('refused by vcu-fsm: '), 'the refusal shown')
    reason = page.text('#command-result')[len('refused by vcu-fsm: '):]
    if len(reason) < 5:
        raise Failure(f'refused without a reason: "{page.text("#command-result")}"')
    log(f'command: set {FSM_KEY} 1 -> "{page.text("#command-result")}"')
    page.screenshot('refused')

    # a schedule command goes to its owner, vcu-can-tx
    page.type('#schedule-key', 'HC1_Demands')
    page.type('#schedule-cycle', '100')
    page.click('#schedule-cycle-button')
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-can-tx', 'the cycle change accepted by vcu-can-tx')
    log(f'command: cycle of HC1_Demands 100 ms -> "{page.text("#command-result")}"')

    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm' and
              page.find(start).get_attribute('data-on') == 'false', 'Stop accepted')
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'the FSM back in Standby after Stop', timeout=30)
    # the battery goes quiet without its keep-alive: the page shows its signal as stale
    page.wait(lambda: page.find(rx_row + ' td.status').get_attribute('data-status') in ('Stale', 'NotConnected'),
              f'{rx_key} stale after Stop', timeout=20)
    log(f'command: Stop accepted, FSM back in Standby; {rx_key} "{page.text(rx_row + " td.status")}", '
        f'age {page.text(rx_row + " td.age")}')


def check_recordings(page, log_path):
    page.click('#tab-recordings')
    recording = page.wait(lambda: page.driver.find_elements(By.CSS_SELECTOR, '#recordings tr[data-kind="recordings"]'),
                          'a recording in #recordings')[0]
    name = recording.get_attribute('data-name')
    href = recording.find_element(By.CSS_SELECTOR, 'a.download-link').get_attribute('href')
    if not href.endswith(f'/api/recordings/{name}/archive'):
        raise Failure(f'download link {href}')
    fetched = page.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "fetch(arguments[0]).then(async (r) => done([r.status, r.headers.get('Content-Type'), (await r.arrayBuffer()).byteLength]))"
        ".catch((e) => done(['error', String(e), 0]));", href)
    if fetched[0] != 200 or not str(fetched[1]).startswith('application/gzip') or fetched[2] < 100:
        raise Failure(f'the download link gives {fetched}')
    log(f'recordings: the download link gives HTTP {fetched[0]} {fetched[1]}, {fetched[2]} bytes')
    recording.find_element(By.CSS_SELECTOR, 'button.summary-button').click()
    page.wait(lambda: 'frames' in recording.find_element(By.CSS_SELECTOR, '.summary-text').text, 'the recording summary')
    log(f'recordings: {name}: {recording.find_element(By.CSS_SELECTOR, ".summary-text").text}; download {href}')
    recording.find_element(By.CSS_SELECTOR, 'a.report-link').click()
    check_report(page, name)
    page.screenshot('recording-report')

    page.find('#upload-file').send_keys(os.path.abspath(log_path))
    page.click('#upload-button')
    page.wait(lambda: page.text('#upload-result').startswith('uploaded as ') and 'frames' in page.text('#upload-result'),
              'the upload analysed', timeout=30)
    uploaded = page.find('#report-frame').get_attribute('data-name')
    log(f'upload: "{page.text("#upload-result")}"')
    check_report(page, uploaded)
    page.wait(lambda: page.driver.find_elements(By.CSS_SELECTOR, f'#recordings tr[data-kind="uploads"][data-name="{uploaded}"]'),
              'the upload listed')
    page.screenshot('upload-report')
    page.click('#tab-live')


def check_report(page, name):
    frame = page.find('#report-frame')
    page.wait(lambda: frame.get_attribute('data-name') == name, f'the report of {name} in #report-frame')
    page.driver.switch_to.frame(frame)
    try:
        text = page.wait(lambda: len(page.driver.find_element(By.TAG_NAME, 'body').text) > 100 and
                         page.driver.find_element(By.TAG_NAME, 'body').text, f'the report of {name} shows', timeout=30)
        headings = [h.text for h in page.driver.find_elements(By.CSS_SELECTOR, 'h1, h2')][:4]
    finally:
        page.driver.switch_to.default_content()
    log(f'report of {name}: {len(text)} characters, headings {headings}')


def check_logout(page):
    page.click('#logout-button')
    page.wait(lambda: page.find('#login-button').is_displayed() and not page.find('#set-button').is_enabled(),
              'the commands disabled after the logout')
    log('logout: the login form is back, commands disabled')


def check_restart(page, kill_command, start_command, user, password):
    page.type('#login-user', user)
    page.type('#login-password', password)
    page.click('#login-button')
    page.wait(lambda: page.text('#whoami') == user, '#whoami before the restart')
    before = page.updates()
    log(f'restart: killing vcu-web ({kill_command}) with the page open, {before} updates received so far')
    subprocess.run(shlex.split(kill_command), check=True, timeout=20)
    killed_at = time.monotonic()
    page.wait(lambda: page.text('#connection') == 'reconnecting', 'the page shows "reconnecting"', timeout=10)
    log(f'restart: "reconnecting" shown {time.monotonic() - killed_at:.1f} s after the kill')
    page.screenshot('reconnecting')
    at_loss = page.updates()  # no event can arrive while vcu-web is down
    subprocess.run(shlex.split(start_command), check=True, timeout=60)
    started_at = time.monotonic()
    page.wait(lambda: page.text('#connection') == 'connected', 'the page reconnects by itself', timeout=20)
    page.wait(lambda: page.updates() > at_loss, 'an update after the reconnect', timeout=10)
    log(f'restart: connected again {time.monotonic() - started_at:.1f} s after the start, updates flow '
        f'({page.updates()} received)')
    # the page must agree with the restarted vcu-web about the session (it keeps sessions in
    # memory: a restart ends them, and the page must show that rather than a stale "alice")
    server_user = page.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "fetch('/api/info').then((r) => r.json()).then((info) => done(info.user)).catch((e) => done('error: ' + e));")
    if server_user is None:
        page.wait(lambda: page.find('#login-button').is_displayed() and not page.find('#whoami').is_displayed(),
                  'the session the restart ended shows as logged out')
        log('restart: the session ended with vcu-web; the page shows the login form again')
        page.type('#login-user', user)
        page.type('#login-password', password)
        page.click('#login-button')
    elif server_user != user:
        raise Failure(f'/api/info after the restart: user {server_user!r}')
    page.wait(lambda: page.text('#whoami') == user, '#whoami after the restart')
    start = f'#operator button[data-key="{START_KEY}"]'
    page.wait(lambda: page.find(start).is_enabled(), 'the switch after the restart')
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'the FSM in Standby after the restart', timeout=30)
    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm', 'Start accepted after the restart')
    page.wait(lambda: page.text('#fsm-state') != 'Standby', 'the FSM state changes after the restart')
    log(f'restart: logged in again, Start accepted, FSM "{page.text("#fsm-state")}"')
    page.screenshot('after-restart')
    page.click(start)
    page.wait(lambda: page.text('#command-result') == 'accepted by vcu-fsm' and
              page.find(start).get_attribute('data-on') == 'false', 'Stop accepted after the restart')


def check_faults(page, fault_on, fault_off):
    """A battery fault injected into the simulated vehicle in Ready: the FSM's fault and the VIC's
    DM1 DTC appear in #faults; cleared and reset from the page, the vehicle stops again."""
    start = f'#operator button[data-key="{START_KEY}"]'
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'the FSM in Standby before the fault case', timeout=30)
    page.click(start)
    page.wait(lambda: page.text('#fsm-state') == 'Ready', 'Ready after Start', timeout=20)
    subprocess.run(shlex.split(fault_on), check=True, timeout=20)
    page.wait(lambda: page.text('#fsm-state') == 'Battery Fault', 'the FSM in Battery Fault', timeout=10)
    faults = page.wait(lambda: [(li.get_attribute('data-name'), li.find_element(By.CSS_SELECTOR, '.source').text)
                                for li in page.driver.find_elements(By.CSS_SELECTOR, '#faults li.fault')]
                       if page.driver.find_elements(By.CSS_SELECTOR, '#faults li.fault[data-name^="dm1."]') else None,
                       'a DM1 DTC in #faults', timeout=10)
    if not any(source == 'vcu-fsm' for _, source in faults):
        raise Failure(f'no fault of vcu-fsm in #faults: {faults}')
    dm1 = page.text('#faults li.fault[data-name^="dm1."]')
    log(f'faults: {faults}; the DM1 row reads "{" ".join(dm1.split())}"')
    page.screenshot('faults')
    subprocess.run(shlex.split(fault_off), check=True, timeout=20)
    page.click('#fault-reset-button')
    page.wait(lambda: page.text('#command-result') not in ('', 'sending…') and
              page.find('#command-result').get_attribute('data-outcome') != 'pending', 'the answer to Reset faults')
    if not page.text('#command-result').startswith('accepted by '):
        raise Failure(f'Reset faults: "{page.text("#command-result")}"')
    page.click(start)
    page.wait(lambda: page.text('#fsm-state') == 'Standby', 'Standby after the fault is cleared and Stop', timeout=30)
    log(f'faults: Reset faults "{page.text("#command-result")}", back in Standby')


def check_console(page):
    """The page's own errors (CSP violations, exceptions) are defects."""
    try:
        entries = page.driver.get_log('browser')
    except WebDriverException:
        return
    # 4xx answers the test provokes are logged too ("Failed to load resource"): only CSP
    # refusals and uncaught exceptions count
    severe = [e for e in entries if e.get('level') == 'SEVERE' and
              ('Refused to' in e.get('message', '') or 'Uncaught' in e.get('message', ''))]
    if severe:
        raise Failure(f'errors in the browser console: {[e["message"] for e in severe][:5]}')


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument('--check-only', action='store_true',
                        help='only check that chromium, chromium-driver and selenium are there (0, or 77)')
    parser.add_argument('--url')
    parser.add_argument('--user')
    parser.add_argument('--log', help='a small candump -L file to upload')
    parser.add_argument('--screenshots', default=os.environ.get('OPENVCU_WEB_SCREENSHOTS', '.'))
    parser.add_argument('--kill-command', help='SIGKILLs vcu-web')
    parser.add_argument('--start-command', help='starts vcu-web again and returns once it listens')
    parser.add_argument('--fault-on-command', help='injects a battery fault into the simulated vehicle')
    parser.add_argument('--fault-off-command', help='clears it')
    args = parser.parse_args()
    if webdriver is None:
        print(f'{NAME}: SKIPPED: python3-selenium is missing ({IMPORT_ERROR})')
        return SKIP
    for program in (CHROMIUM, CHROMEDRIVER):
        if not (os.path.isfile(program) and os.access(program, os.X_OK)):
            print(f'{NAME}: SKIPPED: {program} is missing (Debian packages chromium, chromium-driver)')
            return SKIP
    if args.check_only:
        return 0
    missing = [name for name in ('url', 'user', 'log', 'kill_command', 'start_command', 'fault_on_command',
                                 'fault_off_command') if not getattr(args, name)]
    if missing:
        parser.error(f'missing --{", --".join(m.replace("_", "-") for m in missing)}')
    password = os.environ.get('OPENVCU_WEB_PASSWORD', '')
    if not password:
        print(f'{NAME}: FAIL: OPENVCU_WEB_PASSWORD is not set')
        return 1
    os.makedirs(args.screenshots, exist_ok=True)
    try:
        driver = open_browser()
    except WebDriverException as error:
        print(f'{NAME}: FAIL: chromium did not start: {error.msg}')
        return 1
    page = Page(driver, args.screenshots)
    status = 0
    try:
        rx_key = check_live(page, args.url)
        check_commands(page, args.user, password, rx_key)
        check_recordings(page, args.log)
        check_logout(page)
        check_console(page)
        check_restart(page, args.kill_command, args.start_command, args.user, password)
        check_faults(page, args.fault_on_command, args.fault_off_command)
        check_console(page)  # the entries since the first look (reading the log empties it)
        page.screenshot('final')
        print(f'{NAME}: PASS', flush=True)
    except (Failure, WebDriverException, subprocess.SubprocessError) as failure:
        text = failure.msg if isinstance(failure, WebDriverException) else str(failure)
        print(f'{NAME}: FAIL: {text}', flush=True)
        try:
            driver.save_screenshot(os.path.join(args.screenshots, 'failure.png'))
            log(f'screenshot {os.path.join(args.screenshots, "failure.png")}')
        except WebDriverException:
            pass
        status = 1
    finally:
        driver.quit()
    return status


if __name__ == '__main__':
    sys.exit(main())

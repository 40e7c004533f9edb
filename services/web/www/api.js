// The HTTP half of docs/design/web.md: small fetch wrappers that never throw. Every call
// resolves to {status, body, error}: status 0 when the server could not be reached, body the
// parsed JSON (null when the answer was not JSON), error the server's {"error"} text or a
// description of what went wrong.

async function call(method, path, body, contentType) {
  const init = { method, credentials: 'same-origin', headers: {} };
  if (body !== undefined) {
    init.body = body;
    init.headers['Content-Type'] = contentType;
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (e) {
    return { status: 0, body: null, error: 'vcu-web not reachable' };
  }
  let parsed = null;
  const type = response.headers.get('Content-Type') || '';
  if (type.startsWith('application/json')) {
    try {
      parsed = await response.json();
    } catch (e) {
      parsed = null;
    }
  }
  let error = '';
  if (!response.ok) {
    error = parsed && typeof parsed.error === 'string' ? parsed.error : `HTTP ${response.status}`;
  }
  return { status: response.status, body: parsed, error };
}

export function getJson(path) {
  return call('GET', path);
}

export function postJson(path, object) {
  return call('POST', path, JSON.stringify(object), 'application/json');
}

/// Posts `file` (a File or Blob) as the raw body: the server streams it to disk.
export function postFile(path, file) {
  return call('POST', path, file, 'application/octet-stream');
}

/// "/api/recordings/NAME/report" with NAME escaped as one path component.
export function entryPath(kind, name, what) {
  return `/api/${kind}/${encodeURIComponent(name)}/${what}`;
}

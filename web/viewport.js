// volstyle painting page: the viewport as a live stream (issue #40). The page PUTs its camera and
// render options to …/viewport and reads …/viewport/stream (mjpeg.js): the server renders a
// frame when the viewport moves or what the session shows changes (a solve, an undo, the
// lighting), and a burst of moves renders only the newest. Without a stream (refused, or
// broken) each change is one POST …/render, as before. Loaded before app.js; uses its globals.
'use strict';

const vp = { sid: null, controller: null, live: false, waiters: [], shown: { revision: 0, shown: 0 }, arrivals: [],
             lastBody: '', chain: Promise.resolve(), queued: null, fallbackBusy: false, fallbackPending: false, failedAt: -Infinity };
const kStreamRetryMs = 10000;  // after a refused or broken stream, renders go one by one this long

function viewportRequest() {
  const body = { camera: camera(320), format: 'jpeg' };  // a preview: JPEG encodes in ~1 ms where PNG takes ~10
  if ($('translucent').checked) Object.assign(body, { mode: 'translucent', translucent: translucentOptions() });
  return body;
}

function viewportBusy() { $('viewport-busy').style.display = vp.waiters.length || vp.fallbackBusy ? 'block' : 'none'; }

// Resolves the waits that the frame on screen (or a failed revision) answers.
function settleViewportWaits(key) {
  vp.waiters = vp.waiters.filter((w) => {
    if (key.revision < w.revision || key.shown < w.shown) return true;
    w.resolve();
    return false;
  });
  viewportBusy();
}

function onViewportPart(headers, body) {
  const type = headers['content-type'] || '';
  if (type === 'image/jpeg') {
    const key = { revision: Number(headers['x-revision']), shown: Number(headers['x-shown']) };
    const img = $('viewport'), old = img.src;
    img.src = URL.createObjectURL(new Blob([body], { type }));
    img.dataset.revision = String(key.revision);
    if (old.startsWith('blob:')) URL.revokeObjectURL(old);
    vp.shown = key;
    $('viewport-info').textContent = `version ${headers['x-version']} · ${Number(headers['x-render-ms']).toFixed(0)} ms a frame · ` +
                                     `${streamFrameRate(vp.arrivals).toFixed(1)} fps`;
    settleViewportWaits(key);
  } else if (type === 'application/json') {
    const d = JSON.parse(new TextDecoder().decode(body));
    if (d.event === 'failed') {
      status(`the viewport could not render: ${d.error.message}`, 'error');
      settleViewportWaits({ revision: d.revision, shown: Infinity });
    }
  }  // text/plain: a keep-alive
}

// Opens the session's viewport stream (closing any other); the first PUT follows. A new
// stream starts from nothing: its frames' keys are its session's, from revision 0.
function connectViewport(sid) {
  if (vp.sid === sid && vp.live) return;
  if (vp.controller) vp.controller.abort();
  settleViewportWaits({ revision: Infinity, shown: Infinity });
  const controller = new AbortController();
  Object.assign(vp, { sid, controller, live: true, lastBody: '', arrivals: [], shown: { revision: 0, shown: 0 } });
  readMultipartStream(`${api}/sessions/${sid}/viewport/stream`, controller.signal, onViewportPart)
    .catch((err) => { if (!controller.signal.aborted) status(`the viewport stream stopped (${err.message}): previews are rendered one by one`, 'warn'); })
    .finally(() => {
      if (vp.controller !== controller || controller.signal.aborted) return;
      vp.live = false;  // ended or broken: one render per change for a while, then a new stream
      vp.failedAt = performance.now();
      const waited = vp.waiters.length > 0;
      settleViewportWaits({ revision: Infinity, shown: Infinity });
      if (waited && state.sid === sid) renderViewportOnce();  // what they waited for, the other way
    });
}

// Sends the viewport (or, unchanged, asks where it stands): one request at a time, in order, and
// calls made while one is on its way share the next, which sends the newest state.
function syncViewport() {
  if (vp.queued) return vp.queued;
  const next = vp.chain.then(async () => {
    vp.queued = null;
    const body = JSON.stringify(viewportRequest());
    if (body === vp.lastBody) return call('GET', `/sessions/${state.sid}/viewport`);
    const key = await call('PUT', `/sessions/${state.sid}/viewport`, JSON.parse(body));
    vp.lastBody = body;  // only once the server has it: a failed PUT is sent again next time
    return key;
  });
  vp.queued = next;
  vp.chain = next.catch(() => {});
  return next;
}

// Shows the viewport as the session and the controls are now: resolves once a frame showing
// everything committed before the call is on screen.
async function renderViewport() {
  if (!state.sid) return;
  const retry = performance.now() - vp.failedAt > kStreamRetryMs;
  if (vp.sid !== state.sid || (!vp.live && retry)) connectViewport(state.sid);
  if (!vp.live) return renderViewportOnce();
  let key;
  try {
    key = await syncViewport();
  } catch (e) {  // callers that do not wait (an orbit drag) must not leave a rejection unhandled
    status(e.message, 'error');
    return;
  }
  if (!vp.live || vp.sid !== state.sid) return renderViewportOnce();
  return new Promise((resolve) => {
    vp.waiters.push({ revision: key.revision, shown: key.shown, resolve });
    settleViewportWaits(vp.shown);
  });
}

// Without a stream: one POST …/render in flight, the newest state rendered next.
async function renderViewportOnce() {
  if (vp.fallbackBusy) { vp.fallbackPending = true; return; }
  vp.fallbackBusy = true;
  viewportBusy();
  try {
    const blob = await call('POST', `/sessions/${state.sid}/render`, viewportRequest(), { raw: true });
    $('viewport').src = URL.createObjectURL(blob);
  } catch (e) {
    status(e.message, 'error');
  } finally {
    vp.fallbackBusy = false;
    viewportBusy();
    if (vp.fallbackPending) { vp.fallbackPending = false; renderViewportOnce(); }
  }
}

// volstyle "Light shafts" mode: the session's light-shaft stylizer (docs/STYLIZER.md, docs/API.md).
// Every control edits the scene, which is PUT to …/stylizer (one request in flight, the newest
// state sent next); the server's live stream (…/stylizer/stream, MJPEG) brings each new frame.
// Uses app.js's globals ($, api, call, guard, status). No build step.
'use strict';

(() => {
  const sh = {
    sid: null, scene: null, forest: null, stream: null, arrivals: [], shown: false,
    orbit: { azimuth: 0.2, elevation: 0.1, distance: 11 }, target: [-0.5, 3.2, -2],
    light: { azimuth: -2.56, elevation: 0.58 }, playing: null,
    irradiance: [3.2, 2.9, 2.3], putBusy: false, waiters: [], putPending: false, tfUploaded: false, tfEnabled: false, revision: 0, lastFrameUrl: null,
  };
  const base = () => `/sessions/${sh.sid}/stylizer`;
  const sliders = ['extinction', 'albedo', 'phase-g', 'closing-radius', 'dilation-length', 'hole-frequency',
                   'hole-probability', 'hole-speed', 'time'];
  const num = (id) => Number($(id).value);
  const showOutputs = () => { for (const id of sliders) document.querySelector(`output[for=${id}]`).textContent = $(id).value; };

  // The camera orbits its target; the light's direction (toward the light) is two angles.
  function orbitFromCamera(c) {
    const d = [0, 1, 2].map((k) => c.eye[k] - c.target[k]);
    const r = Math.hypot(...d);
    sh.target = c.target;
    sh.orbit = { distance: r, elevation: Math.asin(d[1] / r), azimuth: Math.atan2(d[0], d[2]) };
  }
  function lightFromDirection(v) {
    const r = Math.hypot(...v);
    sh.light = { elevation: Math.asin(v[1] / r), azimuth: Math.atan2(v[0], v[2]) };
  }
  const unit = (azimuth, elevation) => [Math.sin(azimuth) * Math.cos(elevation), Math.sin(elevation), Math.cos(azimuth) * Math.cos(elevation)];

  function cameraJson() {
    const { azimuth, elevation, distance } = sh.orbit, t = sh.target, d = unit(azimuth, elevation);
    return { eye: t.map((x, k) => x + distance * d[k]), target: t, up: [0, 1, 0], fov_y_deg: 55, width: 480, height: 270, far: 80 };
  }

  // The controls as the scene's fields (the manipulation goes to every occluder but the ground).
  function sceneFromControls() {
    const s = sh.scene;
    s.camera = cameraJson();
    s.medium = { extinction: num('extinction'), albedo: num('albedo'), phase: { type: 'henyey_greenstein', g: num('phase-g') } };
    const toLight = unit(sh.light.azimuth, sh.light.elevation);
    const light = { type: $('light-type').value, direction: toLight, irradiance: sh.irradiance,
                    shadow_map_size: Number($('shadow-map-size').value) };
    if (light.type === 'spot') {  // 16 units away, as bright at the target as the sun was
      light.position = sh.target.map((x, k) => x + 16 * toLight[k]);
      light.cone_deg = 50;
      light.irradiance = sh.irradiance.map((e) => e * 256);  // intensity = irradiance × distance²
    }
    s.light = light;
    const m = {};
    if (num('closing-radius') > 0) m.closing = { radius_px: num('closing-radius'), shape: $('closing-shape').value };
    if (num('dilation-length') > 0) m.dilation = { length: num('dilation-length') };
    if (num('hole-probability') > 0) {
      m.holes = { frequency: num('hole-frequency'), probability: num('hole-probability'), seed: 1, speed: num('hole-speed') };
    }
    for (const o of s.occluders) o.manipulation = o.mesh === 'builtin:forest/ground' ? {} : m;
    s.time = num('time');
    if (sh.tfUploaded && sh.tfEnabled) s.transfer_function = { mode: $('tf-mode').value, depth_range: [0, num('tf-depth')] };
    else delete s.transfer_function;
    if (window.volstyleTf) window.volstyleTf.applyTo(s);  // tf_editor.js: TF layers, the camera path
    return s;
  }

  // One PUT in flight; changes meanwhile are sent together when it answers. The promise settles
  // once a PUT holding this call's state has answered.
  function pushScene() {
    if (!sh.sid || !sh.scene) return Promise.resolve();
    return new Promise((resolve) => {
      sh.waiters.push(resolve);
      if (sh.putBusy) sh.putPending = true;
      else sendScene();
    });
  }
  async function sendScene() {
    sh.putBusy = true;
    const answered = sh.waiters.splice(0);
    $('shafts-busy').style.display = 'block';
    try {
      await call('PUT', base(), sceneFromControls());
    } catch (e) {
      status(e.message, 'error');
      $('shafts-busy').style.display = 'none';
    } finally {
      sh.putBusy = false;
      answered.forEach((resolve) => resolve());
      if (sh.putPending) { sh.putPending = false; sendScene(); }
    }
  }

  // `blob`: the frame's JPEG as the stream brought it (shown without another request).
  async function showFrame(event, blob) {
    sh.revision = event.revision;
    sh.lastFrameUrl = event.url;
    const aov = $('shafts-aov').value;
    let src = event.url;
    if (aov !== 'frame') src = URL.createObjectURL(await call('POST', base() + '/frame', { aov, format: 'png' }, { raw: true }));
    else if (blob) src = URL.createObjectURL(blob);
    const img = $('shafts-frame');
    const shown = img.src;
    img.onload = () => {
      img.dataset.revision = String(event.revision);
      if (shown.startsWith('blob:')) URL.revokeObjectURL(shown);
    };
    img.src = src;
    $('shafts-download').href = event.url;
    if (window.volstyleTf) window.volstyleTf.frameShown();
    const fps = blob ? ` · ${streamFrameRate(sh.arrivals).toFixed(1)} fps` : '';
    $('shafts-info').textContent = `revision ${event.revision} · ${event.width}×${event.height} · ${event.render_ms.toFixed(0)} ms${fps}`;
    if (!sh.putBusy) $('shafts-busy').style.display = 'none';
  }

  // The live stream (…/stylizer/stream): multipart/x-mixed-replace, a JPEG part per frame with its
  // revision and times in the part's headers, a JSON part for a revision that failed or the end.
  // The server sends the newest revision each time, so a slow page skips frames, never lags.
  function onPart(headers, body) {
    const type = headers['content-type'] || '';
    if (type === 'image/jpeg') {
      const revision = Number(headers['x-revision']);
      const event = { revision, url: `${api}${base()}/frames/${revision}.jpeg`, width: Number(headers['x-width']),
                      height: Number(headers['x-height']), render_ms: Number(headers['x-render-ms']) };
      showFrame(event, new Blob([body], { type })).catch((err) => status(err.message, 'error'));
    } else if (type === 'application/json') {
      const d = JSON.parse(new TextDecoder().decode(body));
      if (d.event === 'failed') {
        status(`revision ${d.revision} could not render: ${d.error.message}`, 'error');
        $('shafts-busy').style.display = 'none';
      }
    }  // text/plain: a keep-alive
  }

  function disconnect() {
    if (sh.stream) sh.stream.abort();
    sh.stream = null;
  }
  function connect() {
    disconnect();
    const controller = new AbortController();
    sh.stream = controller;
    sh.arrivals = [];
    readMultipartStream(`${api}${base()}/stream`, controller.signal, onPart).catch((err) => { if (!controller.signal.aborted) status(`the live stream stopped: ${err.message}`, 'error'); });
  }

  function controlsFromScene(s) {
    orbitFromCamera(s.camera);
    lightFromDirection(s.light.direction);
    $('extinction').value = s.medium.extinction;
    $('albedo').value = s.medium.albedo;
    $('phase-g').value = s.medium.phase.g ?? 0;
    $('time').value = s.time;
    $('light-type').value = s.light.type;
    showOutputs();
  }

  const open = guard(async (sid) => {
    sh.sid = sid;
    sh.scene = await call('GET', base());
    if (!sh.forest) sh.forest = JSON.parse(JSON.stringify(sh.scene.occluders));
    controlsFromScene(sh.scene);
    sh.irradiance = sh.scene.light.type === 'spot' ? sh.scene.light.irradiance.map((e) => e / 256) : sh.scene.light.irradiance;
    sh.tfUploaded = false;
    sh.tfEnabled = false;
    $('tf-preview').style.display = 'none';
    $('tf-hint').style.display = '';
    $('tf-remove').disabled = true;
    if (sh.shown) { connect(); await pushScene(); }
  });
  document.addEventListener('volstyle-session', (e) => open(e.detail));
  // The page's first session may have been made before this script ran (app.js runs first and
  // its POST can answer while this file still downloads): the CI run where Light shafts never
  // opened. Take it up here.
  if (typeof state !== 'undefined' && state.sid) open(state.sid);

  function setMode(shafts) {
    sh.shown = shafts;
    $('paint-main').hidden = shafts;
    $('shafts-main').hidden = !shafts;
    $('mode-paint').classList.toggle('selected', !shafts);
    $('mode-shafts').classList.toggle('selected', shafts);
    // The header speaks of the mode on screen: the tab's title and what "Download VDB" gives.
    document.title = shafts ? 'volstyle — light shafts' : 'volstyle — paint your volume';
    $('download-vdb').title = shafts ? 'the session volume (the medium when the scene uses "source": "session")' : 'the volume as painted (its current version)';
    if (shafts && sh.sid) {
      connect();
      pushScene();
      status('light shafts: drag the camera or the light, edit the medium and the shadows, drop a transfer function', 'ok');
    } else {
      disconnect();
      if (!shafts) status('painting: orbit the view, add views, paint them, solve', 'ok');
    }
  }
  $('mode-paint').onclick = () => setMode(false);
  $('mode-shafts').onclick = () => setMode(true);

  for (const id of sliders) $(id).addEventListener('input', () => { showOutputs(); pushScene(); });
  for (const id of ['closing-shape', 'light-type', 'shadow-map-size', 'tf-mode', 'tf-depth']) $(id).addEventListener('change', pushScene);
  $('shafts-aov').addEventListener('change', () => sh.lastFrameUrl && showFrame({ revision: sh.revision, url: sh.lastFrameUrl, width: 480, height: 270, render_ms: 0 }));
  document.querySelectorAll('input[name=drag]').forEach((r) => r.addEventListener('change', () => { $('drag-what').textContent = r.value; }));

  // Dragging the frame orbits the camera or swings the light; the wheel zooms.
  let dragging = null;
  const frame = $('shafts-frame');
  frame.addEventListener('pointerdown', (e) => {
    e.preventDefault();
    if (document.querySelector('input[name=drag]:checked').value === 'constrain') {  // a TF constraint at the pixel
      const r = frame.getBoundingClientRect(), w = frame.naturalWidth || 480, h = frame.naturalHeight || 270;
      const x = Math.min(w - 1, Math.floor((e.clientX - r.left) / r.width * w)), y = Math.min(h - 1, Math.floor((e.clientY - r.top) / r.height * h));
      if (window.volstyleTf) window.volstyleTf.constrainAt(x, y);
      return;
    }
    dragging = { x: e.clientX, y: e.clientY };
    frame.setPointerCapture(e.pointerId);
  });
  frame.addEventListener('pointermove', (e) => {
    if (!dragging) return;
    const dx = (e.clientX - dragging.x) * 0.01, dy = (e.clientY - dragging.y) * 0.01;
    dragging = { x: e.clientX, y: e.clientY };
    const what = document.querySelector('input[name=drag]:checked').value === 'light' ? sh.light : sh.orbit;
    what.azimuth -= dx;
    what.elevation = Math.max(what === sh.light ? 0.05 : -1.2, Math.min(1.5, what.elevation + dy));
    pushScene();
  });
  frame.addEventListener('pointerup', () => { dragging = null; });
  frame.addEventListener('wheel', (e) => {
    e.preventDefault();
    sh.orbit.distance = Math.max(2, Math.min(40, sh.orbit.distance * (e.deltaY > 0 ? 1.1 : 0.9)));
    pushScene();
  }, { passive: false });

  // Time: play advances it (the holes drift with their speed), pause stops.
  $('play').onclick = () => {
    if (sh.playing) {
      clearInterval(sh.playing);
      sh.playing = null;
      $('play').textContent = '▶ Play';
      return;
    }
    $('play').textContent = '❚❚ Pause';
    sh.playing = setInterval(() => {
      $('time').value = (num('time') + 0.1) % Number($('time').max);
      showOutputs();
      pushScene();
    }, 100);
  };

  // Meshes: uploaded under their file name, placed on the ground, scaled to the grove's size.
  const uploadMesh = guard(async (file) => {
    const name = file.name.replace(/\.[^.]*$/, '').replace(/[^A-Za-z0-9_.-]/g, '_').slice(0, 64) || 'mesh';
    status(`uploading ${file.name}…`);
    const m = await call('PUT', `${base()}/occluders/${name}`, file, { type: 'application/octet-stream' });
    const [lo, hi] = m.bounds, size = Math.max(...[0, 1, 2].map((k) => hi[k] - lo[k])) || 1, s = 8 / size;
    const place = [-(lo[0] + hi[0]) / 2 * s, 0.5 - lo[1] * s, -2 - (lo[2] + hi[2]) / 2 * s];
    if (![...$('shafts-scene').options].some((o) => o.value === name)) $('shafts-scene').append(new Option(`${file.name}`, name));
    $('shafts-scene').value = name;
    sh.scene.occluders = [sh.forest[0], { name, mesh: name, colour: [0.35, 0.33, 0.3], manipulation: {},
                                          transform: [s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0, ...place, 1] }];
    await pushScene();
    status(`${file.name} uploaded: ${m.vertices} vertices, ${m.triangles} triangles`, 'ok');
  });
  $('mesh-file').onchange = (e) => e.target.files[0] && uploadMesh(e.target.files[0]);
  $('shafts-scene').onchange = () => {
    const v = $('shafts-scene').value;
    if (v === 'builtin:forest/trees') sh.scene.occluders = JSON.parse(JSON.stringify(sh.forest));
    else sh.scene.occluders = [sh.forest[0], { name: v, mesh: v, colour: [0.35, 0.33, 0.3], manipulation: {},
                                               transform: sh.scene.occluders.find((o) => o.mesh === v)?.transform }];
    if (!sh.scene.occluders[1].transform) delete sh.scene.occluders[1].transform;
    pushScene();
  };

  // The transfer function: dropped or chosen, uploaded, previewed, then used.
  const uploadTf = guard(async (file) => {
    status(`uploading the transfer function ${file.name}…`);
    const t = await call('PUT', `${base()}/tf`, file, { type: 'application/octet-stream' });
    sh.tfUploaded = true;
    sh.tfEnabled = true;
    $('tf-preview').src = `${api}${base()}/tf.png?t=${Date.now()}`;
    $('tf-preview').style.display = 'block';
    $('tf-hint').style.display = 'none';
    $('tf-remove').disabled = false;
    $('tf-remove').textContent = 'No TF';
    await pushScene();
    status(`transfer function ${file.name} (${t.width}×${t.height}, ${t.channels} channels) in use`, 'ok');
  });
  const drop = $('tf-drop');
  drop.addEventListener('dragover', (e) => { e.preventDefault(); drop.classList.add('drop'); });
  drop.addEventListener('dragleave', () => drop.classList.remove('drop'));
  drop.addEventListener('drop', (e) => { e.preventDefault(); drop.classList.remove('drop'); if (e.dataTransfer.files[0]) uploadTf(e.dataTransfer.files[0]); });
  $('tf-file').onchange = (e) => e.target.files[0] && uploadTf(e.target.files[0]);
  $('tf-remove').onclick = () => {
    sh.tfEnabled = !sh.tfEnabled;
    $('tf-remove').textContent = sh.tfEnabled ? 'No TF' : 'Use TF';
    $('tf-preview').style.opacity = sh.tfEnabled ? 1 : 0.35;
    pushScene();
  };
  showOutputs();
  // What tf_editor.js uses.
  window.volstyleShafts = { pushScene, base, cameraJson, tfUploaded: () => sh.tfUploaded, sid: () => sh.sid };
})();

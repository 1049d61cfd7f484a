// volstyle "Light shafts" mode, the transfer-function editor and the camera path (issue #15,
// docs/STYLIZER.md): a stack of TF layers the server compiles (solid, gradient, image, diffusion),
// constraints added on the TF square or by clicking the frame (POST …/stylizer/constraints: the
// pixel's V̄ and depth, optionally following the object), key frames of camera + layers with a
// scrubbed, played and rendered path. The layers and keys go into the scene shafts.js PUTs.
// Uses app.js's globals ($, api, call, guard, status) and shafts.js's window.volstyleShafts.
'use strict';

(() => {
  const sh = window.volstyleShafts;
  const tf = { layers: [], selected: -1, keys: [], playing: null, square: new Image(), drag: null };
  const kTfSize = [128, 128];

  // Colours: the picker's hex as TF values in [0, 1] (the square shows them the same way).
  const hexToRgb = (hex) => [1, 3, 5].map((i) => parseInt(hex.slice(i, i + 2), 16) / 255);
  const rgbToHex = (c) => '#' + c.map((v) => Math.round(Math.min(1, Math.max(0, v)) * 255).toString(16).padStart(2, '0')).join('');
  const brush = () => ({ colour: hexToRgb($('tf-colour').value), alpha: Number($('tf-alpha').value) });

  function newLayer(type) {
    const { colour, alpha } = brush();
    if (type === 'solid') return { type, blend: 'normal', opacity: 1, colour, alpha };
    if (type === 'gradient') {
      return { type, blend: 'multiply', opacity: 1, from: { v_bar: 0, depth: 0.5, colour: [0.3, 0.4, 1], alpha: 1 },
               to: { v_bar: 1, depth: 0.5, colour: [1, 0.8, 0.5], alpha: 1 } };
    }
    if (type === 'image') return { type, blend: 'normal', opacity: 1 };
    return { type: 'diffusion', blend: 'normal', opacity: 1, constraints: [] };
  }

  // The TF as the scene's JSON (null: no layers, the image TF or none applies).
  function tfJson() {
    if (!tf.layers.length) return null;
    return { mode: $('tf-mode').value, depth_range: [0, Number($('tf-depth').value)], size: kTfSize, layers: tf.layers };
  }
  const pathOn = () => $('path-on').checked && tf.keys.length > 0;

  // Called by shafts.js for every scene it sends.
  function applyTo(s) {
    const t = tfJson();
    if (t) s.transfer_function = t;
    if (pathOn()) {
      s.keyframes = tf.keys;
      s.time = Number($('path-time').value);
    } else {
      delete s.keyframes;
    }
  }

  // The compiled TF of the scene (after each new frame) under the selected layer's constraints.
  function frameShown() {
    if (!tf.layers.length) { drawSquare(); return; }
    tf.square.onload = drawSquare;
    tf.square.onerror = drawSquare;
    tf.square.src = `${api}${sh.base()}/transfer_function.png?t=${Date.now()}`;
  }
  function drawSquare() {
    const c = $('tf-square'), g = c.getContext('2d');
    g.clearRect(0, 0, c.width, c.height);
    if (tf.layers.length && tf.square.complete && tf.square.naturalWidth) g.drawImage(tf.square, 0, 0, c.width, c.height);
    const layer = tf.layers[tf.selected];
    if (!layer || layer.type !== 'diffusion') return;
    layer.constraints.forEach((k) => {
      const x = k.v_bar * c.width, y = (1 - k.depth) * c.height;
      g.beginPath();
      g.arc(x, y, 6, 0, 2 * Math.PI);
      g.fillStyle = rgbToHex(k.colour);
      g.fill();
      g.lineWidth = 2;
      g.strokeStyle = k.anchor ? '#7fc97f' : '#ffffff';  // green: follows the scene
      g.stroke();
    });
  }

  // The layer list: select, blend, opacity, colours, move, remove.
  function renderLayers() {
    const list = $('tf-layers');
    list.textContent = '';
    tf.layers.forEach((layer, i) => {
      const li = document.createElement('li');
      li.classList.toggle('selected', i === tf.selected);
      li.dataset.index = String(i);
      const name = document.createElement('span');
      name.textContent = layer.type + (layer.type === 'diffusion' ? ` (${layer.constraints.length})` : '');
      li.append(name);
      const blend = document.createElement('select');
      for (const b of ['normal', 'multiply', 'add']) blend.append(new Option(b, b, false, layer.blend === b));
      blend.onchange = () => { layer.blend = blend.value; changed(); };
      const opacity = document.createElement('input');
      Object.assign(opacity, { type: 'range', min: 0, max: 1, step: 0.05, value: layer.opacity, title: 'opacity' });
      opacity.oninput = () => { layer.opacity = Number(opacity.value); changed(); };
      li.append(blend, opacity);
      const colourInput = (get, set, title) => {
        const input = document.createElement('input');
        Object.assign(input, { type: 'color', value: rgbToHex(get()), title });
        input.oninput = () => { set(hexToRgb(input.value)); changed(); };
        li.append(input);
      };
      if (layer.type === 'solid') colourInput(() => layer.colour, (c) => { layer.colour = c; }, 'colour');
      if (layer.type === 'gradient') {
        colourInput(() => layer.from.colour, (c) => { layer.from.colour = c; }, 'at V̄ = 0');
        colourInput(() => layer.to.colour, (c) => { layer.to.colour = c; }, 'at V̄ = 1');
      }
      const button = (text, title, onclick) => {
        const b = document.createElement('button');
        Object.assign(b, { textContent: text, title });
        b.onclick = (e) => { e.stopPropagation(); onclick(); };
        li.append(b);
      };
      button('▲', 'move up (drawn later)', () => move(i, 1));
      button('▼', 'move down', () => move(i, -1));
      button('✕', 'remove the layer', () => {
        tf.layers.splice(i, 1);
        if (i < tf.selected || tf.selected >= tf.layers.length) tf.selected -= 1;  // the same layer stays selected
        changed();
      });
      li.onclick = () => { tf.selected = i; renderLayers(); drawSquare(); };
      list.append(li);
    });
    $('path-render').disabled = tf.keys.length < 2;
  }
  function move(i, by) {
    const j = i + by;
    if (j < 0 || j >= tf.layers.length) return;
    [tf.layers[i], tf.layers[j]] = [tf.layers[j], tf.layers[i]];
    if (tf.selected === i) tf.selected = j;
    else if (tf.selected === j) tf.selected = i;
    changed();
  }
  function changed() {
    renderLayers();
    drawSquare();
    sh.pushScene();
    if (pathOn() && tf.keys[0].transfer_function) {
      status('viewing the path: the frame shows the key frames\' TFs; uncheck "view the path" to see the layers you edit, or add a key', 'warn');
    }
  }

  $('tf-add').onclick = () => {
    const type = $('tf-add-type').value;
    if (type === 'image' && !sh.tfUploaded()) { status('an image layer shows the uploaded TF: drop one above first', 'warn'); return; }
    tf.layers.push(newLayer(type));
    tf.selected = tf.layers.length - 1;
    changed();
  };
  $('tf-clear').onclick = () => { tf.layers = []; tf.selected = -1; changed(); };
  $('tf-alpha').oninput = () => { document.querySelector('output[for=tf-alpha]').textContent = $('tf-alpha').value; };
  $('tf-alpha').oninput();

  // The TF square: click adds a constraint to the selected diffusion layer, drag moves one,
  // double-click removes it.
  const square = $('tf-square');
  const selectedDiffusion = () => {
    let layer = tf.layers[tf.selected];
    if (!layer || layer.type !== 'diffusion') {
      layer = newLayer('diffusion');
      tf.layers.push(layer);
      tf.selected = tf.layers.length - 1;
    }
    return layer;
  };
  const tfPoint = (e) => {
    const r = square.getBoundingClientRect();
    return { v_bar: Math.min(1, Math.max(0, (e.clientX - r.left) / r.width)), depth: Math.min(1, Math.max(0, 1 - (e.clientY - r.top) / r.height)) };
  };
  const nearest = (layer, p) => layer.constraints.findIndex((k) => Math.hypot(k.v_bar - p.v_bar, k.depth - p.depth) < 0.05);
  square.addEventListener('pointerdown', (e) => {
    e.preventDefault();
    const p = tfPoint(e), layer = selectedDiffusion(), i = nearest(layer, p);
    if (i >= 0) {
      tf.drag = { layer, index: i };
    } else {
      layer.constraints.push({ ...p, ...brush() });
      tf.drag = { layer, index: layer.constraints.length - 1 };
    }
    square.setPointerCapture(e.pointerId);
    changed();
  });
  square.addEventListener('pointermove', (e) => {
    if (!tf.drag) return;
    const k = tf.drag.layer.constraints[tf.drag.index];
    Object.assign(k, tfPoint(e));
    delete k.anchor;  // moved by hand: it keeps this position
    drawSquare();
  });
  square.addEventListener('pointerup', () => { if (tf.drag) { tf.drag = null; changed(); } });
  square.addEventListener('dblclick', (e) => {
    const layer = tf.layers[tf.selected];
    if (!layer || layer.type !== 'diffusion') return;
    const i = nearest(layer, tfPoint(e));
    if (i >= 0) { layer.constraints.splice(i, 1); changed(); }
  });

  // A click on the frame: the server picks the pixel and adds the constraint to the scene; the
  // page then takes the layers back from it.
  const constrainAt = guard(async (x, y) => {
    await sh.pushScene();  // the scene the click was made on is the server's
    const layer = tf.layers[tf.selected];
    const body = { x, y, ...brush(), anchor: $('tf-follow').checked ? 'object' : 'none' };
    if (layer && layer.type === 'diffusion') body.layer = tf.selected;
    if (pathOn() && tf.keys[0].transfer_function) delete body.layer;  // the server picks the nearest key's layer
    const added = await call('POST', `${sh.base()}/constraints`, body);
    const scene = await call('GET', sh.base());  // the server applied it: take its layers (and keys) back
    if (added.key !== undefined) {
      tf.keys = scene.keyframes;
      renderKeys();
    } else {
      tf.layers = scene.transfer_function.layers;
      tf.selected = added.layer;
    }
    $('tf-picked').textContent = `pixel (${x}, ${y}): V̄ ${added.pick.v_bar.toFixed(3)}, depth ${added.pick.depth.toFixed(3)}` +
                                 (added.constraint.anchor ? ` · follows ${added.constraint.anchor.follow || 'the point'}` : '');
    renderLayers();
    drawSquare();
    status(`TF constraint added at V̄ ${added.pick.v_bar.toFixed(3)}, depth ${added.pick.depth.toFixed(3)}` +
           (added.key !== undefined ? ` to key frame ${added.key + 1}` : ''), 'ok');
  });
  document.querySelectorAll('input[name=drag]').forEach((r) => r.addEventListener('change', () => {
    $('shafts-frame').style.cursor = r.value === 'constrain' ? 'crosshair' : 'grab';
  }));

  // The camera path: keys at 2 s apart; the slider scrubs it (viewing the path), play animates.
  function renderKeys() {
    const list = $('keys');
    list.textContent = '';
    tf.keys.forEach((k, i) => {
      const li = document.createElement('li');
      li.textContent = `t = ${k.time.toFixed(1)} s · ${k.transfer_function ? k.transfer_function.layers.length + ' layers' : 'no TF'} `;
      const go = document.createElement('button');
      Object.assign(go, { textContent: 'view', title: 'scrub to this key' });
      go.onclick = () => { $('path-on').checked = true; $('path-time').value = k.time; scrubbed(); };
      const remove = document.createElement('button');
      Object.assign(remove, { textContent: '✕', title: 'remove the key' });
      remove.onclick = () => { tf.keys.splice(i, 1); keysChanged(); };
      li.append(go, remove);
      list.append(li);
    });
    const last = tf.keys.length ? tf.keys[tf.keys.length - 1].time : 0;
    $('path-time').max = String(last);
    $('path-play').disabled = tf.keys.length < 2;
    $('path-render').disabled = tf.keys.length < 2;
  }
  function keysChanged() { renderKeys(); sh.pushScene(); }
  function scrubbed() {
    document.querySelector('output[for=path-time]').textContent = Number($('path-time').value).toFixed(2);
    sh.pushScene();
  }
  $('key-add').onclick = () => {
    const time = tf.keys.length ? tf.keys[tf.keys.length - 1].time + 2 : 0;
    const key = { time, camera: sh.cameraJson() };
    const t = tfJson();
    if (t) key.transfer_function = JSON.parse(JSON.stringify(t));
    if (tf.keys.length && !!tf.keys[0].transfer_function !== !!key.transfer_function) {
      status('every key has TF layers or none does: add layers (or clear them) to match the first key', 'warn');
      return;
    }
    tf.keys.push(key);
    keysChanged();
    status(`key frame ${tf.keys.length} at t = ${time} s`, 'ok');
  };
  $('path-on').onchange = () => sh.pushScene();
  $('path-time').oninput = () => { $('path-on').checked = true; scrubbed(); };
  $('path-play').onclick = () => {
    if (tf.playing) {
      clearInterval(tf.playing);
      tf.playing = null;
      $('path-play').textContent = '▶ Play';
      return;
    }
    $('path-on').checked = true;
    $('path-play').textContent = '❚❚ Pause';
    tf.playing = setInterval(() => {
      const max = Number($('path-time').max), t = Number($('path-time').value) + 0.1;
      $('path-time').value = String(t > max + 1e-9 ? 0 : t);
      scrubbed();
    }, 150);
  };

  // The whole path as frames and an MP4, by a server job; its progress, then the video.
  $('path-render').onclick = guard(async () => {
    $('path-on').checked = true;
    await sh.pushScene();
    const fps = Number($('path-fps').value);
    const { job } = await call('POST', `${sh.base()}/sequence`, { fps, video: true });
    const bar = $('path-progress');
    bar.hidden = false;
    $('path-video').hidden = true;
    const events = new EventSource(`${api}/jobs/${job}/events`);
    events.addEventListener('progress', (e) => {
      const p = JSON.parse(e.data);
      bar.max = p.frames;
      bar.value = p.frame;
      status(`rendering the path: frame ${p.frame} of ${p.frames}`);
    });
    const end = (e, ok) => {
      events.close();
      bar.hidden = true;
      const j = JSON.parse(e.data);
      if (!ok) { status(`the sequence failed: ${j.error ? j.error.message : 'cancelled'}`, 'error'); return; }
      $('path-video').href = j.result.video_url;
      $('path-video').hidden = false;
      status(`sequence rendered: ${j.result.frames} frames at ${j.result.fps} fps`, 'ok');
    };
    events.addEventListener('done', (e) => end(e, true));
    events.addEventListener('failed', (e) => end(e, false));
    events.addEventListener('cancelled', (e) => end(e, false));
  });

  window.volstyleTf = { applyTo, frameShown, constrainAt };
  renderLayers();
  renderKeys();
})();

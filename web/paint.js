// Painting a view (issue #37: paint that means what it shows). The base under the brush is the
// view's linear render (its EXR, medium over background), shown at an exposure the artist picks,
// with stripes where it is brighter than the screen. The target sent is linear float (EXR): a
// stroke's colour means what it shows at that exposure (sRGB on screen → linear ÷ 2^exposure),
// laid over the base's true values by the stroke's alpha, so clipping on screen never reaches the
// solve. Unpainted pixels keep the render exactly (weight 1) when "Keep the rest" is ticked, and
// ask nothing (weight 0) when it is not; erased pixels always ask nothing. Needs app.js and exr.js.
'use strict';

const paint = $('paint'), ctx = paint.getContext('2d');
const mask = document.createElement('canvas');
mask.width = paint.width; mask.height = paint.height;
const maskCtx = mask.getContext('2d');
let drawing = false;
let base = null;  // { view, width, height, rgb: Float32Array(3·w·h) }: the linear picture under the paint

const srgbToLinear = (c) => (c <= 0.04045 ? c / 12.92 : ((c + 0.055) / 1.055) ** 2.4);
const linearToSrgb = (c) => (c <= 0.0031308 ? 12.92 * c : 1.055 * c ** (1 / 2.4) - 0.055);
const exposure = () => Number($('paint-exposure').value);

function clearPaint() {
  ctx.clearRect(0, 0, paint.width, paint.height);
  maskCtx.clearRect(0, 0, mask.width, mask.height);
}

function clearBase() {
  base = null;
  const c = $('paint-base');
  c.getContext('2d').clearRect(0, 0, c.width, c.height);
  delete c.dataset.view;
  $('clip-warning').hidden = true;
}

// The picture a render's EXR shows, as the solve reads it (core pictureOf): the medium plus its
// transmittance times the background; a file without those layers is its RGB.
function pictureOf(exr) {
  const { width, height, channels: c } = exr, n = width * height, rgb = new Float32Array(3 * n);
  ['R', 'G', 'B'].forEach((k, j) => {
    const m = c[k], t = c['transmittance.' + k], b = c['background.' + k];
    for (let i = 0; i < n; ++i) rgb[3 * i + j] = m[i] + (t && b ? t[i] * b[i] : 0);
  });
  return { width, height, rgb };
}

async function loadBase(id) {
  const res = await fetch(`${api}/sessions/${state.sid}/views/${id}/render.exr?t=${Date.now()}`);
  if (!res.ok) throw new Error(`the render of ${id} did not load (${res.status})`);
  const picture = pictureOf(await readExr(await res.arrayBuffer()));
  if (state.selected !== id) return;  // another view was chosen meanwhile
  base = { view: id, ...picture };
  drawBase();
}

// The base at the chosen exposure; pixels brighter than the screen get diagonal stripes and the
// warning says how many (what the old 8-bit base silently flattened to white).
function drawBase() {
  if (!base) return;
  const c = $('paint-base'), { width, height, rgb } = base;
  c.width = width; c.height = height;
  const g = c.getContext('2d'), img = g.createImageData(width, height), gain = 2 ** exposure();
  let clipped = 0;
  for (let y = 0, i = 0; y < height; ++y)
    for (let x = 0; x < width; ++x, ++i) {
      const r = rgb[3 * i] * gain, gr = rgb[3 * i + 1] * gain, b = rgb[3 * i + 2] * gain;
      const clips = Math.max(r, gr, b) > 1;
      clipped += clips;
      const stripe = clips && ((x + y) >> 2) % 2 === 0 ? 0.45 : 1;
      [r, gr, b].forEach((v, j) => { img.data[4 * i + j] = 255 * stripe * linearToSrgb(Math.min(1, Math.max(0, v))); });
      img.data[4 * i + 3] = 255;
    }
  g.putImageData(img, 0, 0);
  c.dataset.view = base.view;
  const share = clipped / (width * height), w = $('clip-warning');
  w.hidden = clipped === 0;
  w.dataset.clipped = String(clipped);
  w.textContent = `${(100 * share).toFixed(1)}% of ${base.view} is brighter than the screen at ${formatStops(exposure())} (striped): ` +
                  'lower the exposure (or Auto) to see it; the target keeps its true values';
}

const formatStops = (e) => `${e >= 0 ? '+' : ''}${e.toFixed(2)} stops`;

function showExposure() {
  $('paint-exposure-value').textContent = formatStops(exposure());
  drawBase();
}

// Auto: the exposure (in quarter stops) at which 99.5% of the base's pixels fit the screen.
function autoExposure() {
  if (!base) return;
  const peaks = [];
  for (let i = 0; i < base.rgb.length; i += 3) peaks.push(Math.max(base.rgb[i], base.rgb[i + 1], base.rgb[i + 2]));
  peaks.sort((a, b) => a - b);
  const p = peaks[Math.min(peaks.length - 1, Math.floor(0.995 * peaks.length))];
  const e = p > 0 ? Math.floor(-Math.log2(p) * 4) / 4 : 0;
  const input = $('paint-exposure');
  input.value = String(Math.max(Number(input.min), Math.min(Number(input.max), e)));
  showExposure();
}

const selectView = guard(async (id) => {
  state.selected = id;
  $('paint-view').textContent = id;
  $('download-view').href = `${api}/sessions/${state.sid}/views/${id}/render.png`;
  $('download-view').download = `${id}.png`;
  $('download-view-exr').href = `${api}/sessions/${state.sid}/views/${id}/render.exr?exr_type=float`;
  $('download-view-exr').download = `${id}.exr`;
  clearPaint();
  clearBase();
  renderViews();
  await loadBase(id);
});

function stroke(e) {
  const r = paint.getBoundingClientRect();
  const x = (e.clientX - r.left) * paint.width / r.width, y = (e.clientY - r.top) * paint.height / r.height;
  const size = Number($('brush-size').value) * paint.width / 256;
  if ($('eraser').checked) {
    maskCtx.fillStyle = '#000';
    maskCtx.beginPath(); maskCtx.arc(x, y, size, 0, 2 * Math.PI); maskCtx.fill();
    ctx.globalAlpha = 1; ctx.fillStyle = 'rgba(20,20,20,0.65)';
  } else {
    ctx.globalAlpha = Number($('brush-opacity').value) / 100; ctx.fillStyle = $('brush-colour').value;
  }
  ctx.beginPath(); ctx.arc(x, y, size, 0, 2 * Math.PI); ctx.fill();
  ctx.globalAlpha = 1;
}
paint.addEventListener('pointerdown', (e) => { if (!state.selected) return; drawing = true; paint.setPointerCapture(e.pointerId); stroke(e); });
paint.addEventListener('pointermove', (e) => { if (drawing) stroke(e); });
paint.addEventListener('pointerup', () => { drawing = false; });

// A canvas's pixels scaled to the base's size.
function pixelsAt(canvas, width, height) {
  const c = document.createElement('canvas');
  c.width = width; c.height = height;
  const g = c.getContext('2d');
  g.drawImage(canvas, 0, 0, width, height);
  return g.getImageData(0, 0, width, height).data;
}

// The target: linear RGB and weight (alpha) per pixel, as an EXR.
function paintedTarget() {
  const { width, height, rgb } = base, n = width * height;
  const strokes = document.createElement('canvas');  // the strokes, less what the eraser marked
  strokes.width = paint.width; strokes.height = paint.height;
  const s = strokes.getContext('2d');
  s.drawImage(paint, 0, 0);
  s.globalCompositeOperation = 'destination-out';
  s.drawImage(mask, 0, 0);
  const p = pixelsAt(strokes, width, height), m = pixelsAt(mask, width, height);
  const keep = $('keep-rest').checked, gain = 2 ** -exposure();
  const channels = { R: new Float32Array(n), G: new Float32Array(n), B: new Float32Array(n), A: new Float32Array(n) };
  let painted = 0;
  for (let i = 0; i < n; ++i) {
    const a = p[4 * i + 3] / 255;
    ['R', 'G', 'B'].forEach((k, j) => {
      channels[k][i] = a * srgbToLinear(p[4 * i + j] / 255) * gain + (1 - a) * rgb[3 * i + j];
    });
    painted += a > 0;
    channels.A[i] = m[4 * i + 3] > 0 ? 0 : a > 0 || keep ? 1 : 0;
  }
  return { exr: writeExr({ width, height, channels }), painted };
}

const uploadTarget = guard(async () => {
  if (!state.selected) throw new Error('add a view first');
  if (!base || base.view !== state.selected) await loadBase(state.selected);
  const { exr, painted } = paintedTarget();
  await call('PUT', `/sessions/${state.sid}/views/${state.selected}/target`, exr, { type: 'image/x-exr' });
  await refreshViews();
  const rest = $('keep-rest').checked ? 'the rest kept as it renders' : 'the rest left free';
  status(`target of ${state.selected} uploaded: linear EXR, ${painted} painted pixels at ${formatStops(exposure())}, ${rest}`, 'ok');
});

const dropTarget = guard(async (file) => {
  if (!state.selected) throw new Error('add a view first, then drop its painted target');
  await call('PUT', `/sessions/${state.sid}/views/${state.selected}/target`, file, { type: file.type || 'application/octet-stream' });
  await refreshViews();
  status(`${file.name} is the target of ${state.selected}`, 'ok');
});

// Drag and drop of painted images onto the paint area.
const wrap = $('paint-wrap');
wrap.addEventListener('dragover', (e) => { e.preventDefault(); wrap.classList.add('drop'); });
wrap.addEventListener('dragleave', () => wrap.classList.remove('drop'));
wrap.addEventListener('drop', (e) => { e.preventDefault(); wrap.classList.remove('drop'); if (e.dataTransfer.files[0]) dropTarget(e.dataTransfer.files[0]); });

$('paint-exposure').addEventListener('input', showExposure);
$('paint-auto').onclick = autoExposure;
$('clear-paint').onclick = clearPaint;
$('upload-target').onclick = uploadTarget;
showExposure();

// OpenEXR in the page, just what painting needs (issue #37): read a view's render (scanline,
// NONE/ZIPS/ZIP compression, HALF or FLOAT channels: what the server writes) and write a painted
// target (scanline, NONE, FLOAT RGBA). The layout follows "OpenEXR File Layout"
// (openexr.com/en/latest/OpenEXRFileLayout.html). No build step: classic script, globals below.
'use strict';

const kExrMagic = 20000630;
const kExrPixelBytes = { 1: 2, 2: 4 };       // HALF, FLOAT (UINT is not read)
const kExrLinesPerChunk = { 0: 1, 2: 1, 3: 16 };  // NONE, ZIPS, ZIP

// IEEE 754 half → number.
function exrHalf(h) {
  const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
  if (e === 0) return s * m * 2 ** -24;
  if (e === 31) return m ? NaN : s * Infinity;
  return s * (1 + m / 1024) * 2 ** (e - 15);
}

function exrReadHeader(view) {
  if (view.getInt32(0, true) !== kExrMagic) throw new Error('not an OpenEXR file');
  const flags = view.getUint32(4, true);
  if (flags & 0x1200) throw new Error('tiled or multi-part EXR: the page reads scanline files only');
  let at = 8;
  const text = () => {
    let s = '';
    for (let c; (c = view.getUint8(at++)) !== 0;) s += String.fromCharCode(c);
    return s;
  };
  const header = {};
  for (let name; (name = text()) !== '';) {
    text();  // the attribute's type: implied by its name for the few read here
    const size = view.getInt32(at, true), start = at + 4;
    if (name === 'channels') {
      header.channels = [];
      at = start;
      for (let c; (c = text()) !== '';) {
        header.channels.push({ name: c, type: view.getInt32(at, true) });
        at += 16;  // type, pLinear + reserved, xSampling, ySampling
      }
    } else if (name === 'compression') {
      header.compression = view.getUint8(start);
    } else if (name === 'dataWindow') {
      const [x0, y0, x1, y1] = [0, 4, 8, 12].map((o) => view.getInt32(start + o, true));
      header.window = { x0, y0, width: x1 - x0 + 1, height: y1 - y0 + 1 };
    }
    at = start + size;
  }
  header.chunksAt = at;
  return header;
}

// ZIP/ZIPS chunk: zlib, then the encoder's byte predictor and its two-halves interleave undone.
async function exrInflate(bytes, rawSize) {
  if (bytes.length === rawSize) return bytes;  // the writer stores a chunk raw when zlib would not shrink it
  const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream('deflate'));
  const t = new Uint8Array(await new Response(stream).arrayBuffer());
  for (let i = 1; i < t.length; ++i) t[i] = (t[i - 1] + t[i] - 128) & 0xff;
  const out = new Uint8Array(t.length), half = (t.length + 1) >> 1;
  for (let i = 0; i < t.length; ++i) out[i] = i & 1 ? t[half + (i >> 1)] : t[i >> 1];
  return out;
}

// Reads an EXR into { width, height, channels: { name: Float32Array(width·height) } }, rows top
// to bottom (increasing y, as the file's data window).
async function readExr(buffer) {
  const view = new DataView(buffer);
  const h = exrReadHeader(view);
  if (!(h.compression in kExrLinesPerChunk)) throw new Error(`EXR compression ${h.compression}: the page reads NONE, ZIPS and ZIP`);
  for (const c of h.channels) if (!(c.type in kExrPixelBytes)) throw new Error(`EXR channel ${c.name}: UINT is not read`);
  const { width, height } = h.window, lines = kExrLinesPerChunk[h.compression];
  const rowBytes = h.channels.reduce((n, c) => n + width * kExrPixelBytes[c.type], 0);
  const channels = Object.fromEntries(h.channels.map((c) => [c.name, new Float32Array(width * height)]));
  const chunks = Math.ceil(height / lines);
  for (let k = 0; k < chunks; ++k) {
    const offset = Number(view.getBigUint64(h.chunksAt + 8 * k, true));
    const y0 = view.getInt32(offset, true) - h.window.y0, size = view.getInt32(offset + 4, true);
    const n = Math.min(lines, height - y0);
    const packed = new Uint8Array(buffer, offset + 8, size);
    const data = h.compression === 0 ? packed : await exrInflate(packed, n * rowBytes);
    const d = new DataView(data.buffer, data.byteOffset, data.byteLength);
    let at = 0;
    for (let y = y0; y < y0 + n; ++y)
      for (const c of h.channels) {
        const dst = channels[c.name], row = y * width;
        for (let x = 0; x < width; ++x, at += kExrPixelBytes[c.type])
          dst[row + x] = c.type === 2 ? d.getFloat32(at, true) : exrHalf(d.getUint16(at, true));
      }
  }
  return { width, height, channels };
}

// Writes { width, height, channels: { R, G, B, A: Float32Array } } as a scanline EXR, FLOAT, no
// compression (a 256² RGBA target is 1 MiB: small beside a solve, and exact).
function writeExr({ width, height, channels }) {
  const names = Object.keys(channels).sort();  // the file lists channels in alphabetical order
  const parts = [];
  const bytes = (n, fill) => { const b = new DataView(new ArrayBuffer(n)); fill(b); parts.push(b.buffer); };
  const text = (s) => parts.push(new TextEncoder().encode(s + '\0').buffer);
  const attribute = (name, type, size, fill) => { text(name); text(type); bytes(4, (b) => b.setInt32(0, size, true)); bytes(size, fill); };
  bytes(8, (b) => { b.setInt32(0, kExrMagic, true); b.setUint32(4, 2, true); });
  const chlist = names.reduce((n, c) => n + c.length + 1 + 16, 1);
  attribute('channels', 'chlist', chlist, (b) => {
    let at = 0;
    for (const c of names) {
      for (const ch of c) b.setUint8(at++, ch.charCodeAt(0));
      at += 1;
      b.setInt32(at, 2, true);  // FLOAT
      b.setInt32(at + 8, 1, true);
      b.setInt32(at + 12, 1, true);
      at += 16;
    }
  });
  attribute('compression', 'compression', 1, (b) => b.setUint8(0, 0));
  for (const name of ['dataWindow', 'displayWindow'])
    attribute(name, 'box2i', 16, (b) => { b.setInt32(8, width - 1, true); b.setInt32(12, height - 1, true); });
  attribute('lineOrder', 'lineOrder', 1, (b) => b.setUint8(0, 0));
  attribute('pixelAspectRatio', 'float', 4, (b) => b.setFloat32(0, 1, true));
  attribute('screenWindowCenter', 'v2f', 8, () => {});
  attribute('screenWindowWidth', 'float', 4, (b) => b.setFloat32(0, 1, true));
  text('');
  const headerBytes = parts.reduce((n, p) => n + p.byteLength, 0);
  const rowBytes = 4 * width * names.length;
  bytes(8 * height, (b) => {
    for (let y = 0; y < height; ++y) b.setBigUint64(8 * y, BigInt(headerBytes + 8 * height + y * (8 + rowBytes)), true);
  });
  for (let y = 0; y < height; ++y)
    bytes(8 + rowBytes, (b) => {
      b.setInt32(0, y, true);
      b.setInt32(4, rowBytes, true);
      let at = 8;
      for (const c of names)
        for (let x = 0; x < width; ++x, at += 4) b.setFloat32(at, channels[c][y * width + x], true);
    });
  return new Blob(parts, { type: 'image/x-exr' });
}

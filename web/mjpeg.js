// volstyle's live streams as the page reads them (docs/API.md): multipart/x-mixed-replace, one
// part per event — a JPEG frame with its revision and times in the part's headers, a JSON part
// for a revision that failed or the stream's end, an empty text/plain part as keep-alive. Used by
// the painting viewport (…/viewport/stream) and the light-shaft mode (…/stylizer/stream).
'use strict';

// Reads the stream at `url` until it ends or `signal` aborts; onPart(headers, body) for each part
// (header names in lower case, body a Uint8Array). Throws on a refused or broken stream.
async function readMultipartStream(url, signal, onPart) {
  const res = await fetch(url, { signal });
  if (!res.ok) throw new Error(`the live stream answered ${res.status}`);
  const reader = res.body.getReader();
  let buf = new Uint8Array(0);
  const more = async () => {
    const { value, done } = await reader.read();
    if (done) return false;
    const b = new Uint8Array(buf.length + value.length);
    b.set(buf);
    b.set(value, buf.length);
    buf = b;
    return true;
  };
  const headEnd = () => {
    for (let i = 0; i + 3 < buf.length; ++i) if (buf[i] === 13 && buf[i + 1] === 10 && buf[i + 2] === 13 && buf[i + 3] === 10) return i;
    return -1;
  };
  for (;;) {
    let end;
    while ((end = headEnd()) < 0) if (!(await more())) return;
    const headers = {};
    for (const line of new TextDecoder().decode(buf.subarray(0, end)).split('\r\n')) {
      const colon = line.indexOf(':');
      if (colon > 0) headers[line.slice(0, colon).trim().toLowerCase()] = line.slice(colon + 1).trim();
    }
    const start = end + 4, length = Number(headers['content-length'] || 0);
    while (buf.length < start + length + 2) if (!(await more())) return;
    const body = buf.slice(start, start + length);
    buf = buf.slice(start + length + 2);  // the part's closing CRLF
    if (signal.aborted) return;
    onPart(headers, body);
  }
}

// Frames per second over the last two seconds of `arrivals` (times in ms; the newest is pushed).
function streamFrameRate(arrivals) {
  const now = performance.now();
  arrivals.push(now);
  while (arrivals.length > 1 && now - arrivals[0] > 2000) arrivals.shift();
  return arrivals.length > 1 ? (arrivals.length - 1) * 1000 / (now - arrivals[0]) : 0;
}

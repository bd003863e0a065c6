// SPDX-License-Identifier: MIT
// A .pmz read by byte ranges for view-dependent decoding (Decoder.updateView): the stream in
// order up to its node table, then the ranges of the nodes a view needs (Decoder.nodesToFetch),
// a few requests in flight, each response checked before its bytes are fed. A stream without a
// node table (or with attributes), or a server that ignores Range (200 instead of 206), is read
// on in order with feed(). Every request has an idle timeout; no response body is read past
// the bytes asked for.
const FLAG_ATTRIBUTES = 1, FLAG_NODES = 2;  // HEAD flags (spec/format.md)
const PREFIX_MAX = 4 << 20;  // in-order ranges before the node table grow up to this

// The first, last and total of a Content-Range header ("bytes a-b/n", n may be "*": -1).
function contentRange(header) {
  const m = /^\s*bytes\s+(\d+)-(\d+)\/(\d+|\*)\s*$/i.exec(header || '');
  return m ? { first: Number(m[1]), last: Number(m[2]), total: m[3] === '*' ? -1 : Number(m[3]) } : null;
}

export class RangeSource {
  // options: init (fetch()'s RequestInit: headers, credentials, ...), inFlight (requests at
  // once, 4), timeoutMs (a request fails when no byte arrives for this long, 30000),
  // firstBytes (the first in-order range, 16 KiB; each next one twice as large), mergeBytes
  // (nodes adjacent in the file are asked for in one request up to this size, 1 MiB),
  // onData() (after bytes were fed).
  constructor(decoder, url, options = {}) {
    this.decoder = decoder;
    this.url = String(url);
    this.init = options.init ?? {};
    this.inFlight = Math.max(1, options.inFlight ?? 4);
    this.timeoutMs = options.timeoutMs ?? 30000;
    this.firstBytes = Math.max(1024, options.firstBytes ?? 16384);
    this.mergeBytes = options.mergeBytes ?? 1 << 20;
    this.onData = options.onData ?? null;
    this.bytes = 0;  // response bytes received
    this.totalBytes = 0;  // the file's size once a response said it (0: not known)
    this.requests = 0;
    this.nodesFetched = 0;
    // Reading the rest in order: a stream without a node table or with attributes, or a server
    // that ignores Range.
    this.inOrder = false;
    this.error = '';  // the first failed request or response, one line ('' while none)
    this._fed = 0;  // stream bytes fed in order
    this._nodes = new Map();  // node -> 'flight' | 'done'
    this._queue = [];  // {k, offset, size} wanted, not requested, most wanted first
    this._active = 0;  // node requests in flight
    this._reading = false;  // reading in order (open() or a 200)
    this._controllers = new Set();
    this._waiters = [];
    this._closed = false;
  }

  // Nothing in flight or queued, and no in-order reading: nothing more arrives without want().
  get idle() { return this._active === 0 && !this._reading && this._queue.length === 0; }
  // Resolves once something arrived or failed (or at once when idle).
  changed() {
    if (this.idle || this.error) return Promise.resolve();
    return new Promise((resolve) => this._waiters.push(resolve));
  }
  _wake() {
    for (const resolve of this._waiters.splice(0)) resolve();
  }

  // Reads the stream in order until its node table arrived; a stream that has none (or has
  // attributes), or a server that ignores Range, is read to its end in order. Resolves then
  // (the decoder's status says whether the bytes were good); rejects on a failed request or a
  // bad response (also in `error`).
  async open() {
    this._reading = true;
    try {
      let size = this.firstBytes;
      for (;;) {
        const d = this.decoder;
        if (this._closed || d.status !== 'ok' || d.nodeRange(1)) return;
        const info = d.info();
        if (info.complete || (this.totalBytes && this._fed >= this.totalBytes)) {
          d.finish();
          return;
        }
        if (info.headerDone && (!(info.flags & FLAG_NODES) || info.flags & FLAG_ATTRIBUTES)) {
          this.inOrder = true;  // refined in file order: the rest in one request
          await this._readInOrder(await this._request(this._fed));
          return;
        }
        let last = this._fed + size - 1;
        if (this.totalBytes) last = Math.min(last, this.totalBytes - 1);
        const req = await this._request(this._fed, last);
        if (req.response.status === 200) {
          this.inOrder = true;
          await this._readInOrder(req);
          return;
        }
        const bytes = await this._read(req, this._fed, last, true);
        this._fed += bytes.length;
        d.feed(bytes);
        if (this.onData) this.onData();
        size = Math.min(2 * size, PREFIX_MAX);
      }
    } catch (e) {
      throw this._failed(e);
    } finally {
      this._reading = false;
      this._wake();
    }
  }

  // The nodes to fetch now (Decoder.nodesToFetch(), most wanted first): those neither in flight
  // nor arrived are queued in that order (replacing what was queued and is no longer wanted)
  // and requested as requests finish.
  want(ids) {
    if (this.inOrder || this.error || this._closed) return;
    this._queue = [];
    for (const k of ids) {
      if (this._nodes.has(k)) continue;
      const r = this.decoder.nodeRange(k);
      if (!r) continue;
      const end = r.offset + r.size;
      // The node the in-order reading stopped in: its rest, fed in order (not its whole range
      // again).
      if (r.offset < this._fed && this._fed < end)
        this._queue.push({ k, offset: this._fed, size: end - this._fed, inOrder: true });
      else
        this._queue.push({ k, offset: r.offset, size: r.size });
    }
    this._pump();
  }

  _pump() {
    while (!this.inOrder && !this.error && !this._closed && this._active < this.inFlight &&
           this._queue.length) {
      // The first queued node and those right after it in the file, in one request.
      const group = [this._queue.shift()];
      let end = group[0].offset + group[0].size;
      for (;;) {
        const i = this._queue.findIndex((q) => q.offset === end);
        if (i < 0 || end - group[0].offset + this._queue[i].size > this.mergeBytes) break;
        const [q] = this._queue.splice(i, 1);
        group.push(q);
        end += q.size;
      }
      for (const q of group) this._nodes.set(q.k, 'flight');
      ++this._active;
      this._fetchNodes(group, end).catch((e) => this._failed(e)).finally(() => {
        --this._active;
        for (const q of group) if (this._nodes.get(q.k) === 'flight') this._nodes.delete(q.k);
        this._wake();
        this._pump();
      });
    }
  }

  async _fetchNodes(group, end) {
    const first = group[0].offset;
    const req = await this._request(first, end - 1);
    if (req.response.status === 200) {  // Range ignored: the rest of the stream in order
      if (this.inOrder) { req.cancel(); return; }
      this.inOrder = true;
      for (const c of this._controllers) if (c !== req.controller) c.abort();
      this._reading = true;
      try {
        await this._readInOrder(req);
      } finally {
        this._reading = false;
      }
      return;
    }
    const bytes = await this._read(req, first, end - 1, false);
    for (const q of group) {
      if (this.decoder.status !== 'ok' || this._closed) return;
      const piece = bytes.subarray(q.offset - first, q.offset - first + q.size);
      if (q.inOrder) {
        this.decoder.feed(piece);
        this._fed += piece.length;
      } else {
        this.decoder.feedNode(q.k, piece);
      }
      this._nodes.set(q.k, 'done');
      ++this.nodesFetched;
    }
    if (this.onData) this.onData();
  }

  // fetch() with `Range: bytes=first-last` (last undefined: to the end), aborted when no byte
  // arrives for timeoutMs. Resolves once the headers are in: {response, controller, arm()
  // (restarts the timeout), cancel(), done()}; rejects on a network error, a timeout or a status
  // other than 200 and 206.
  async _request(first, last) {
    const controller = new AbortController();
    this._controllers.add(controller);
    const range = `bytes=${first}-${last ?? ''}`;
    let timer = null, timedOut = false;
    const req = {
      controller, range,
      arm: () => {
        clearTimeout(timer);
        timer = setTimeout(() => { timedOut = true; controller.abort(); }, this.timeoutMs);
      },
      done: () => {
        clearTimeout(timer);
        this._controllers.delete(controller);
      },
      cancel: () => { req.done(); controller.abort(); },
      timedOut: () => timedOut,
    };
    req.arm();
    const headers = new Headers(this.init.headers);
    headers.set('Range', range);
    ++this.requests;
    try {
      req.response = await fetch(this.url, { ...this.init, headers, signal: controller.signal });
    } catch (e) {
      req.done();
      throw new Error(this._where(range) + (timedOut ? `no response within ${this.timeoutMs / 1000} s`
        : String(e && e.message ? e.message : e).split('\n')[0]));
    }
    const status = req.response.status;
    if (status !== 200 && status !== 206) {
      req.cancel();
      throw new Error(this._where(range) + `HTTP ${status}`);
    }
    return req;
  }

  _where(range) { return `pmz: ${this.url} (${range}): `; }

  // A 206's body, checked: Content-Range must be first-last (or up to the file's end when
  // toEnd), Content-Length and the bytes read its size.
  async _read(req, first, last, toEnd) {
    const r = req.response, fail = (why) => { req.cancel(); return new Error(this._where(req.range) + why); };
    const cr = contentRange(r.headers.get('content-range'));
    if (!cr || cr.first !== first || cr.last < cr.first ||
        !(cr.last === last || (toEnd && cr.last < last && cr.last === cr.total - 1)) ||
        (cr.total >= 0 && cr.last >= cr.total)) {
      throw fail(`the server sent Content-Range "${r.headers.get('content-range') ?? ''}"`);
    }
    if (cr.total >= 0) this.totalBytes = cr.total;
    const size = cr.last - cr.first + 1;
    const length = r.headers.get('content-length');
    if (length !== null && Number(length) !== size) throw fail(`Content-Length ${length} for ${size} bytes`);
    const out = new Uint8Array(size);
    let at = 0;
    await this._pour(req, (value) => {
      if (at + value.length > size) throw fail(`more than the ${size} bytes asked for`);
      out.set(value, at);
      at += value.length;
      return true;
    });
    if (at !== size) throw new Error(this._where(req.range) + `the body ended after ${at} of ${size} bytes`);
    return out;
  }

  // Reads req's body, each piece to take(piece) (false: stop there, cancelling the rest),
  // restarting the timeout at each. Resolves to true when the body ended, false when stopped or
  // closed; rejects on a timeout or a network error (one line).
  async _pour(req, take) {
    const reader = req.response.body.getReader();
    try {
      for (;;) {
        const { done, value } = await reader.read();
        if (done) break;
        req.arm();
        this.bytes += value.length;
        if (!take(value)) {
          req.cancel();
          return false;
        }
      }
    } catch (e) {
      req.cancel();
      if (this._closed) return false;
      if (req.timedOut()) throw new Error(this._where(req.range) + `no data for ${this.timeoutMs / 1000} s`);
      if (String(e && e.message).startsWith('pmz: ')) throw e;
      throw new Error(this._where(req.range) + String(e && e.message ? e.message : e).split('\n')[0]);
    } finally {
      reader.releaseLock();
    }
    req.done();
    return true;
  }

  // A body read in order into feed() from the bytes already fed on: a 206 for `bytes=N-` or a
  // 200 (the whole file: its first bytes, fed already, are skipped). finish() at its end.
  async _readInOrder(req) {
    const r = req.response;
    let at = 0;  // the body's first byte in the stream
    if (r.status === 206) {
      const cr = contentRange(r.headers.get('content-range'));
      if (!cr || cr.first !== this._fed) {
        req.cancel();
        throw new Error(this._where(req.range) +
                        `the server sent Content-Range "${r.headers.get('content-range') ?? ''}"`);
      }
      at = cr.first;
      if (cr.total >= 0) this.totalBytes = cr.total;
    } else {
      this.totalBytes = Number(r.headers.get('content-length')) || this.totalBytes;
    }
    const d = this.decoder;
    const whole = await this._pour(req, (value) => {
      const skip = Math.max(0, this._fed - at);
      at += value.length;
      if (skip < value.length) {
        this._fed += value.length - skip;
        d.feed(value.subarray(skip));
        if (this.onData) this.onData();
        this._wake();
      }
      return d.status === 'ok' && !this._closed;
    });
    if (whole) d.finish();
  }

  // The first failure is kept (in error) and stops every request; returns it as an Error.
  _failed(e) {
    const message = String(e && e.message ? e.message : e).split('\n')[0];
    if (!this.error && !this._closed) {
      this.error = message;
      this._abort();
    }
    this._wake();
    return new Error(this.error || message);
  }

  _abort() {
    this._queue = [];
    for (const c of this._controllers) c.abort();
    this._controllers.clear();
    this._wake();
  }

  // Stops every request.
  close() {
    this._closed = true;
    this._abort();
  }
}

// Decodes what `view` (Decoder.updateView()'s argument) needs from the .pmz at url, fetched by
// ranges (see RangeSource; options are its options, maxSplits, the splits per updateView(), and
// maxFaces, the face budget: Decoder.setViewFaceBudget(), 0 or absent: none).
// Resolves to {status (the decoder's), complete (every node the view needs is applied), bytes
// (received), totalBytes, requests, nodesFetched, inOrder}; rejects on a failed request or a
// bad response.
export async function loadView(decoder, url, view, options = {}) {
  const source = new RangeSource(decoder, url, options);
  try {
    await source.open();
    decoder.setViewFaceBudget(options.maxFaces);
    for (;;) {
      if (source.error) throw new Error(source.error);
      const moved = decoder.updateView(view, options.maxSplits);
      if (decoder.status !== 'ok' || decoder.viewComplete()) break;
      source.want(decoder.nodesToFetch());
      if (moved > 0) continue;  // the split budget ran out: more is ready
      if (source.idle) break;  // nothing more comes: the file ends before what the view needs
      await source.changed();
    }
    if (source.error) throw new Error(source.error);
  } finally {
    source.close();
  }
  return { status: decoder.status, complete: decoder.viewComplete(), bytes: source.bytes,
    totalBytes: source.totalBytes, requests: source.requests, nodesFetched: source.nodesFetched,
    inOrder: source.inOrder };
}

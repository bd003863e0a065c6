// SPDX-License-Identifier: MIT
// pmz web viewer: the drawing side (render.js) in a Web Worker, on the page's canvas transferred
// to it (OffscreenCanvas). The page's thread then never waits for a drawn frame: with software
// compositing (headless Chromium, SwiftShader) each drawn WebGL frame is read back, and that
// wait now happens on this thread. Decoding runs in a worker of its own (PMZLoader's worker.js,
// started from here) unless ?worker=0.
import { createView } from './render.js';

let view = null;
self.onmessage = (e) => {
  const m = e.data;
  if (m.type === 'init') {
    try {
      if (typeof requestAnimationFrame !== 'function') throw new Error('no requestAnimationFrame in workers');
      view = createView({ ...m, post: (message) => self.postMessage(message) });
      self.postMessage({ type: 'ready', timeOrigin: performance.timeOrigin });
    } catch (err) {  // no WebGL2 here: the page draws itself
      self.postMessage({ type: 'unavailable', error: String(err && err.message ? err.message : err) });
    }
  } else if (view) {
    view.handle(m);
  }
};

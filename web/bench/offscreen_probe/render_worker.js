// SPDX-License-Identifier: MIT
// The probe's drawing worker: the grid drawn on the transferred canvas every animation frame of
// this worker for ms; posts its frame times on the page's clock.
import * as THREE from './three.module.js';
import { makeScene } from './scene.js';

self.onmessage = (e) => {
  const { canvas, width, height, faces, ms, timeOrigin } = e.data;
  const frames = [], offset = performance.timeOrigin - timeOrigin;
  try {
    const draw = makeScene(THREE, canvas, width, height, faces);
    const start = performance.now();
    const frame = (t) => {
      frames.push(t + offset);
      draw(t);
      if (performance.now() - start < ms) requestAnimationFrame(frame);
      else self.postMessage({ frames });
    };
    requestAnimationFrame(frame);
  } catch (err) {
    self.postMessage({ frames, error: String(err) });
  }
};

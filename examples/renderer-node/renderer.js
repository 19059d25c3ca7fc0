#!/usr/bin/env node
// A renderer outside Python, plugged in with YAML alone (renderer.yaml beside it), in persistent
// mode: started once, it greets with {"ok": true}, then answers one JSON line per render request.
// It draws the probe sphere as brdf-remap's conventions say (docs/adapters.md): a pinhole camera
// looking at the target from +z, +y up, row 0 at the top; point lights of radiant intensity
// I (W/sr), irradiance I cos / d^2; a Lambertian albedo/pi plus a normalised Blinn-Phong lobe
// specular colour times (n+2)/(2 pi) cos^n of the half-vector; direct light only; each pixel the mean of spp
// jittered samples (a box filter), repeatable for one seed. It writes PFM (float32 linear RGB).
"use strict";
const fs = require("fs");
const readline = require("readline");

function rng(seed) {  // mulberry32: the same seed, the same samples
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
const norm = (a) => scale(a, 1 / Math.sqrt(dot(a, a)));

function shade(p, n, v, lights, m) {
  const out = [0, 0, 0];
  for (const light of lights) {
    const toLight = sub(light.position, p);
    const d2 = dot(toLight, toLight);
    const l = scale(toLight, 1 / Math.sqrt(d2));
    const cos = dot(n, l);
    if (cos <= 0) continue;
    const e = (light.intensity * cos) / d2;
    const h = norm([l[0] + v[0], l[1] + v[1], l[2] + v[2]]);
    const lobe = ((m.exponent + 2) / (2 * Math.PI)) * Math.pow(Math.max(dot(n, h), 0), m.exponent);
    for (let c = 0; c < 3; c++) out[c] += e * (m.diffuse[c] / Math.PI + m.specular[c] * lobe);
  }
  return out;
}

function render(scene, params, path) {
  const w = scene.width, h = scene.height, cam = scene.camera, sphere = scene.sphere;
  const eye = cam.position, fwd = norm(sub(cam.target, eye));
  const right = norm(cross(fwd, cam.up)), up = cross(right, fwd);
  const t = Math.tan((cam.fov * Math.PI) / 360);
  const m = { diffuse: params.diffuse, specular: params.specular, exponent: params.exponent };
  const next = rng(scene.seed * 9781 + 1);
  const pixels = new Float32Array(w * h * 3);
  for (let j = 0; j < h; j++) {
    for (let i = 0; i < w; i++) {
      const sum = [0, 0, 0];
      for (let s = 0; s < scene.spp; s++) {
        const x = ((2 * (i + next())) / w - 1) * t, y = (1 - (2 * (j + next())) / h) * t * (h / w);
        const d = norm([fwd[0] + x * right[0] + y * up[0], fwd[1] + x * right[1] + y * up[1],
                        fwd[2] + x * right[2] + y * up[2]]);
        const oc = sub(eye, sphere.center);
        const b = dot(oc, d), disc = b * b - (dot(oc, oc) - sphere.radius * sphere.radius);
        if (disc < 0) continue;
        const dist = -b - Math.sqrt(disc);
        if (dist <= 0) continue;
        const p = [eye[0] + dist * d[0], eye[1] + dist * d[1], eye[2] + dist * d[2]];
        const rgb = shade(p, norm(sub(p, sphere.center)), scale(d, -1), scene.lights, m);
        for (let c = 0; c < 3; c++) sum[c] += rgb[c];
      }
      for (let c = 0; c < 3; c++) pixels[(j * w + i) * 3 + c] = sum[c] / scene.spp;
    }
  }
  // PFM: a text header, then little-endian float32 rows from the bottom of the image up.
  const body = Buffer.alloc(w * h * 12);
  for (let j = 0; j < h; j++) {
    for (let k = 0; k < w * 3; k++) body.writeFloatLE(pixels[(h - 1 - j) * w * 3 + k], (j * w * 3 + k) * 4);
  }
  fs.writeFileSync(path, Buffer.concat([Buffer.from(`PF\n${w} ${h}\n-1.0\n`), body]));
}

function answer(msg) {
  process.stdout.write(JSON.stringify(msg) + "\n");
}

const input = readline.createInterface({ input: process.stdin });
input.on("line", (line) => {
  let req;
  try {
    req = JSON.parse(line);
  } catch (err) {
    answer({ ok: false, error: `not JSON: ${err.message}` });
    return;
  }
  if (req.op === "quit") process.exit(0);
  try {
    if (req.scene.lights.some((light) => light.type !== "point")) throw new Error("point lights only");
    render(req.scene, req.params, req.output);
    answer({ id: req.id, ok: true });
  } catch (err) {
    process.stderr.write(`${err.stack}\n`);
    answer({ id: req.id, ok: false, error: err.message });
  }
});
answer({ ok: true });

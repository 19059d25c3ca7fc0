// The probe scene in three.js, driven by the threejs adapter (adapters/threejs/browser.py): a sphere
// with a glTF material (read by three.js's own GLTFLoader, as an app reads it), point lights in W/sr
// (three.js's physical units: candela, inverse-square decay), an environment through three.js's own
// PMREM, rendered into a float render target: linear radiance, no tone mapping, no output transform.
import * as THREE from "three";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { USDLoader } from "three/addons/loaders/USDLoader.js";

const canvas = document.createElement("canvas");
document.body.appendChild(canvas);
let lost = false;
canvas.addEventListener("webglcontextlost", (e) => { lost = true; e.preventDefault(); });
const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, alpha: false, preserveDrawingBuffer: false });
renderer.toneMapping = THREE.NoToneMapping;
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
const gl = renderer.getContext();
const floatTargets = !!gl.getExtension("EXT_color_buffer_float");
const pmrem = new THREE.PMREMGenerator(renderer);
const loader = new GLTFLoader();
const usdLoader = new USDLoader();
const environments = new Map();
const spheres = new Map();
const targets = new Map();

// The probe sphere, with tangents along its latitudes (d position / d phi; the bitangent up), as a
// written file's sphere has (TANGENT) and as glTF asks a viewer to make them where a file has none:
// anisotropy turns from them. (Without them three.js derives a frame from the texture coordinates'
// screen-space derivatives, neither unit nor orthogonal on a sphere.) A textured sphere has the
// probe's texture coordinates (core/data/textures.py: u = phi / 2pi from +x, increasing away from a
// viewer on +z; v = theta / pi from the top pole, an image's top row at v = 0, as glTF reads
// images): three.js's sphere begun half a turn round (its vertices are the same), its v turned over.
function sphere(radius, textured) {
  const key = `${radius} ${textured}`;
  if (!spheres.has(key)) {
    const start = textured ? Math.PI : 0;
    const g = new THREE.SphereGeometry(radius, 256, 128, start);
    const uv = g.attributes.uv, tangents = new Float32Array(uv.count * 4);
    for (let i = 0; i < uv.count; i++) {
      const phi = start + 2 * Math.PI * uv.getX(i);  // three.js's: x = -cos(phi) sin(theta), z = sin(phi) sin(theta)
      tangents.set([Math.sin(phi), 0, Math.cos(phi), 1], 4 * i);
      if (textured) uv.setY(i, 1 - uv.getY(i));
    }
    g.setAttribute("tangent", new THREE.BufferAttribute(tangents, 4));
    spheres.set(key, g);
  }
  return spheres.get(key);
}

function target(n) {
  if (!targets.has(n)) {
    targets.set(n, new THREE.WebGLRenderTarget(n, n, { type: THREE.FloatType, format: THREE.RGBAFormat,
      minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: true }));
  }
  return targets.get(n);
}

function decode(b64) {
  const bin = atob(b64), bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}

function encode(floats) {
  const bytes = new Uint8Array(floats.buffer);
  let bin = "";
  for (let i = 0; i < bytes.length; i += 0x8000) bin += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
  return btoa(bin);
}

// An equirectangular map of linear radiance, RGBA float rows bottom first as three.js samples them
// (the adapter turns the project's convention into three.js's), prefiltered by three.js's PMREM.
function setEnvironment(key, width, height, b64) {
  if (environments.has(key)) return;
  const tex = new THREE.DataTexture(decode(b64), width, height, THREE.RGBAFormat, THREE.FloatType);
  tex.mapping = THREE.EquirectangularReflectionMapping;
  tex.colorSpace = THREE.LinearSRGBColorSpace;
  tex.magFilter = THREE.LinearFilter;
  tex.minFilter = THREE.LinearFilter;
  tex.needsUpdate = true;
  const rt = pmrem.fromEquirectangular(tex);
  tex.dispose();
  environments.set(key, rt.texture);
}

async function material(doc) {
  const gltf = await loader.parseAsync(JSON.stringify(doc), "");
  return gltf.parser.getDependency("material", 0);
}

// The material of a USD layer's first mesh, as three.js's own USDLoader reads it (a UsdPreviewSurface
// into MeshPhysicalMaterial), the layer's geometry dropped.
async function usdMaterial(text) {
  const group = await new Promise((resolve, reject) => usdLoader.parse(text, "", resolve, reject));
  let found = null;
  group.traverse((o) => { if (o.isMesh) { if (!found) found = o.material; o.geometry.dispose(); } });
  if (!found) throw new Error("three.js's USDLoader found no mesh with a material in the layer");
  return found;
}

function renderView(mesh, view, n) {
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0, 0, 0);
  scene.add(mesh);
  for (const light of view.lights) {
    if (light.type === "point") {
      const p = new THREE.PointLight(0xffffff, light.intensity, 0, 2);
      p.position.set(...light.position);
      scene.add(p);
    } else {
      if (!environments.has(light.key)) throw new Error(`environment ${light.key} was not set`);
      scene.environment = environments.get(light.key);
    }
  }
  const c = view.camera;
  const camera = new THREE.PerspectiveCamera(c.fov, 1, 0.01 * c.distance, 100 * c.distance);
  camera.position.set(...c.position);
  camera.up.set(...c.up);
  camera.lookAt(...c.target);
  const rt = target(n);
  renderer.setRenderTarget(rt);
  renderer.render(scene, camera);
  const pixels = new Float32Array(n * n * 4);
  renderer.readRenderTargetPixels(rt, 0, 0, n, n, pixels);
  renderer.setRenderTarget(null);
  scene.remove(mesh);
  return pixels;
}

// The mean of each ss x ss block, rows top first (a float target reads bottom row first).
function downsample(pixels, r, ss, out, offset) {
  const n = r * ss, w = 1 / (ss * ss);
  for (let y = 0; y < r; y++) for (let x = 0; x < r; x++) {
    let a = 0, b = 0, c = 0;
    for (let j = 0; j < ss; j++) {
      const row = ((r - 1 - y) * ss + j) * n;
      for (let i = 0; i < ss; i++) {
        const k = (row + x * ss + i) * 4;
        a += pixels[k]; b += pixels[k + 1]; c += pixels[k + 2];
      }
    }
    const o = offset + (y * r + x) * 3;
    out[o] = a * w; out[o + 1] = b * w; out[o + 2] = c * w;
  }
}

async function render(req) {
  if (lost) throw new Error("the WebGL context was lost");
  const t0 = performance.now();
  const mat = req.usda !== undefined ? await usdMaterial(req.usda) : await material(req.material);
  const mesh = new THREE.Mesh(sphere(req.sphere.radius, !!req.sphere.textured), mat);
  mesh.position.set(...req.sphere.center);
  const r = req.resolution, ss = req.supersample;
  const out = new Float32Array(r * r * 3 * req.views.length);
  req.views.forEach((view, i) => downsample(renderView(mesh, view, r * ss), r, ss, out, i * r * r * 3));
  for (const value of Object.values(mat)) if (value && value.isTexture) value.dispose();
  mat.dispose();
  if (lost) throw new Error("the WebGL context was lost");
  return { pixels: encode(out), ms: performance.now() - t0 };
}

window.brdf = {
  info: () => ({ three: THREE.REVISION, webgl2: true, floatTargets, renderer: gl.getParameter(gl.RENDERER) }),
  setEnvironment,
  render,
};
window.brdfReady = true;

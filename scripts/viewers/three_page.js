// The three.js side of make evaluation-viewers, run inside headless Chromium by three_render.mjs (which serves
// this file, three.js and the assets over a local HTTP server). window.renderJob(job) loads one glTF with
// GLTFLoader, lights it only by an equirectangular HDR map turned into the scene's environment (PMREMGenerator),
// frames it with the fixed camera of docs/evaluation.md ("What viewers show") and renders it into a float render
// target: linear radiance, no tone mapping, no output encoding, transparent background (alpha = coverage).
// It returns the pixels as base64 of a Float32Array, RGBA, top row first, box-filtered from `supersample`² samples
// per pixel (each itself 4x MSAA).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { boxFilter, toBase64 } from 'matremap/readback.js';

const revision = parseInt(THREE.REVISION, 10);

// r180 renamed RGBELoader to HDRLoader (the old name still works but warns).
async function hdrLoader() {
    if (revision >= 180) return new (await import('three/addons/loaders/HDRLoader.js')).HDRLoader();
    return new (await import('three/addons/loaders/RGBELoader.js')).RGBELoader();
}

// Mean luminance (Rec. 709) of an equirectangular map, each row weighted by its solid angle.
function meanLuminance(data, width, height) {
    let sum = 0, weights = 0;
    for (let y = 0; y < height; y++) {
        const w = Math.cos(((y + 0.5) / height - 0.5) * Math.PI);
        for (let x = 0; x < width; x++) {
            const i = 4 * (y * width + x);
            sum += w * (0.2126 * data[i] + 0.7152 * data[i + 1] + 0.0722 * data[i + 2]);
        }
        weights += w * width;
    }
    return sum / weights;
}

const environments = new Map(); // url -> {texture, scale}, kept across jobs with the same renderer

async function environment(renderer, url, meanTarget) {
    if (environments.has(url)) return environments.get(url);
    const loader = await hdrLoader();
    loader.setDataType(THREE.FloatType);
    const hdr = await loader.loadAsync(url);
    const { data, width, height } = hdr.image;
    // Scale the map to a mean luminance of meanTarget, as the Blender side does (blender_render.py).
    const scale = meanTarget / meanLuminance(data, width, height);
    for (let i = 0; i < data.length; i++) if (i % 4 !== 3) data[i] *= scale;
    hdr.needsUpdate = true;
    hdr.mapping = THREE.EquirectangularReflectionMapping;
    const pmrem = new THREE.PMREMGenerator(renderer);
    const target = pmrem.fromEquirectangular(hdr);
    pmrem.dispose();
    hdr.dispose();
    const env = { texture: target.texture, scale };
    environments.set(url, env);
    return env;
}

// Bounding sphere of the scene's vertices (world space): the same framing as blender_render.py, in glTF's axes.
function frame(camera, object, view) {
    object.updateMatrixWorld(true);
    const box = new THREE.Box3().setFromObject(object, true);
    const centre = box.getCenter(new THREE.Vector3());
    const radius = 0.5 * box.getSize(new THREE.Vector3()).length();
    const az = view.azimuth * Math.PI / 180, el = view.elevation * Math.PI / 180;
    const dir = new THREE.Vector3(Math.sin(az) * Math.cos(el), Math.sin(el), Math.cos(az) * Math.cos(el));
    const distance = view.margin * radius / Math.sin(0.5 * view.fov * Math.PI / 180);
    camera.fov = view.fov;
    camera.aspect = 1;
    camera.near = 0.01 * distance;
    camera.far = 10 * distance;
    camera.position.copy(centre).addScaledVector(dir, distance);
    camera.up.set(0, 1, 0);
    camera.lookAt(centre);
    camera.updateProjectionMatrix();
}

// A core-only engine: the glTF's JSON with the material extensions `strip` names removed (from every material and
// from extensionsUsed/Required) before GLTFLoader parses it, so it reads what an engine without them reads.
async function loadGltf(url, strip) {
    const loader = new GLTFLoader();
    if (strip.length === 0) return loader.loadAsync(url);
    const json = await (await fetch(url)).json();
    for (const m of json.materials || []) {
        if (!m.extensions) continue;
        for (const e of strip) delete m.extensions[e];
    }
    for (const key of ['extensionsUsed', 'extensionsRequired']) {
        if (json[key]) json[key] = json[key].filter((e) => !strip.includes(e));
    }
    return loader.parseAsync(JSON.stringify(json), url.substring(0, url.lastIndexOf('/') + 1));
}

let renderer = null;

window.renderJob = async (job) => {
    const started = performance.now();
    const size = job.size, ss = job.supersample, big = size * ss;
    if (!renderer) {
        renderer = new THREE.WebGLRenderer({ antialias: false, alpha: true });
        renderer.setPixelRatio(1);
        renderer.setSize(16, 16);
        renderer.toneMapping = THREE.NoToneMapping;
    }
    const scene = new THREE.Scene();
    const env = await environment(renderer, job.env, job.envMean);
    scene.environment = env.texture;
    const gltf = await loadGltf(job.gltf, job.strip || []);
    scene.add(gltf.scene);
    const extensions = new Set();
    scene.traverse((o) => {
        if (o.isMesh) {
            const mats = Array.isArray(o.material) ? o.material : [o.material];
            for (const m of mats) extensions.add(m.type + (m.isGLTFSpecularGlossinessMaterial ? ' (spec-gloss)' : ''));
        }
    });
    const camera = new THREE.PerspectiveCamera();
    frame(camera, gltf.scene, job.view);
    const target = new THREE.WebGLRenderTarget(big, big, { type: THREE.FloatType, samples: 4 });
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(scene, camera);
    const pixels = new Float32Array(big * big * 4);
    renderer.readRenderTargetPixels(target, 0, 0, big, big, pixels);
    renderer.setRenderTarget(null);
    target.dispose();
    scene.traverse((o) => {
        if (o.isMesh) {
            o.geometry.dispose();
            const mats = Array.isArray(o.material) ? o.material : [o.material];
            for (const m of mats) {
                for (const v of Object.values(m)) if (v && v.isTexture) v.dispose();
                m.dispose();
            }
        }
    });
    // Box filter ss x ss blocks; WebGL's row 0 is the bottom row, the output's is the top.
    const out = boxFilter(pixels, size, ss);
    return {
        pixels: toBase64(out), revision: THREE.REVISION, materials: [...extensions], envScale: env.scale,
        seconds: (performance.now() - started) / 1000,
    };
};
window.viewerReady = true;

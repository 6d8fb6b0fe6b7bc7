// The three.js side of make evaluation-clients (docs/evaluation-clients.md), run inside headless Chromium by
// client_render.mjs, which serves this file, three.js and the job's files over a local HTTP server.
// window.renderClientJob(job) opens one material of a document that `matremap export` (or the library's writer)
// wrote, through three.js's own loaders:
//   - a MaterialX document (.mtlx) through MaterialXLoader (node materials: WebGPURenderer, here on its WebGL2
//     backend, forceWebGL, as headless Chromium has no WebGPU adapter);
//   - a USD layer (.usda) through USDLoader: the layer's text is parsed with one extra prim appended, a one-triangle
//     Mesh bound to the material (`rel material:binding`), so that USDComposer builds the material exactly as it
//     does for a mesh of a scene (the layer has materials only); the material is taken from that mesh.
//   - format gltf: the export's source as GLTFLoader reads it (a material of a mesh-less glTF by name, or, with a
//     mesh, the asset's own materials): the same BRDF as matremap's gltf model, the renderer floor.
// The material is put on a UV sphere (radius 1, 256 x 128 segments; matremap's fit scene: camera at (0, 0, 4)
// looking down -z, 35 degrees vertical field of view) or on the meshes of a glTF asset (geometry only, through
// GLTFLoader; its texture coordinates flipped to v' = 1 - v, from glTF's top-left origin to the bottom-left origin
// of USD and MaterialX documents, unless job.noUvFlip), framed as matremap frames an asset (mr_camera_frame_mesh:
// the bounding box's centre, the farthest vertex's distance as radius, at radius / sin(0.9 * fov / 2) along
// job.cameraDirection). job.uvSpace, when given, is passed to MaterialXLoader (its default: 'bottom-left').
// It is lit only by an equirectangular HDR map (scene.environment through PMREMGenerator), scaled to a mean
// luminance of envMean (solid-angle weighted, as three_page.js does) and turned by scene.environmentRotation so that
// its directions are matremap's (docs/rendering.md: the map's centre at -z, u = 0.75 at +x): three.js reads
// direction d at u = atan2(d.z, d.x) / 2 pi + 0.5, which puts u = 0.5 at +x and u = 0.75 at +z, a quarter turn
// away; the rotation is the job's envRotation (radians about +y; docs/evaluation-clients.md, how it was measured).
// Rendered into a float render target (linear radiance, no tone mapping, no output colour space, transparent
// background: alpha = coverage), box-filtered from supersample^2 samples per pixel (each 4x MSAA). Returns the
// pixels (base64 of a Float32Array, RGBA, top row first) and what the loader reported.
import * as THREE from 'three/webgpu';
import { MaterialXLoader } from 'three/addons/loaders/MaterialXLoader.js';
import { USDLoader } from 'three/addons/loaders/USDLoader.js';
import { HDRLoader } from 'three/addons/loaders/HDRLoader.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { boxFilter, toBase64 } from 'matremap/readback.js';

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

let renderer = null;
const environments = new Map();

async function environment(url, meanTarget) {
    if (environments.has(url)) return environments.get(url);
    const loader = new HDRLoader();
    loader.setDataType(THREE.FloatType);
    const hdr = await loader.loadAsync(url);
    const { data, width, height } = hdr.image;
    const scale = meanTarget / meanLuminance(data, width, height);
    for (let i = 0; i < data.length; i++) if (i % 4 !== 3) data[i] *= scale;
    hdr.needsUpdate = true;
    hdr.mapping = THREE.EquirectangularReflectionMapping;
    const pmrem = new THREE.PMREMGenerator(renderer);
    const target = pmrem.fromEquirectangular(hdr);
    pmrem.dispose();
    const env = { texture: target.texture, scale };
    environments.set(url, env);
    return env;
}

// The material of a .mtlx document: MaterialXLoader's materials by name, its log's warnings and errors.
async function mtlxMaterial(url, name, report, uvSpace) {
    const result = await new MaterialXLoader().loadAsync(url, { throwOnErrors: false, materialName: name, uvSpace });
    for (const w of result.warnings || []) report.warnings.push(`${w.code}: ${w.message}`);
    for (const e of result.errors || []) report.errors.push(`${e.code}: ${e.message}`);
    const material = result.materials[name];
    if (!material) throw new Error(`${url}: no material '${name}' (has ${Object.keys(result.materials).join(', ')})`);
    return material;
}

// The material of a .usda layer: the layer with a probe mesh bound to /Materials/NAME, through USDLoader.parse.
async function usdaMaterial(url, name, report) {
    const text = await (await fetch(url)).text();
    const probe = `\ndef Mesh "MatremapClientProbe" (\n    prepend apiSchemas = ["MaterialBindingAPI"]\n)\n{\n` +
        '    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n' +
        '    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n' +
        `    rel material:binding = </Materials/${name}>\n}\n`;
    const base = url.slice(0, url.lastIndexOf('/') + 1);
    const group = await new Promise((ok, fail) => new USDLoader().parse(text + probe, base, ok, fail));
    let material = null;
    group.traverse((o) => { if (o.isMesh && o.name === 'MatremapClientProbe') material = o.material; });
    if (!material) throw new Error(`${url}: USDLoader built no probe mesh for material '${name}'`);
    report.usd = {
        type: material.type, color: material.color.toArray(), metalness: material.metalness,
        roughness: material.roughness, ior: material.ior, specularColor: material.specularColor.toArray(),
        specularIntensity: material.specularIntensity, clearcoat: material.clearcoat,
        clearcoatRoughness: material.clearcoatRoughness,
        maps: ['map', 'metalnessMap', 'roughnessMap', 'normalMap', 'specularColorMap'].filter((k) => material[k]),
    };
    return material;
}

// A material of a glTF file (one without meshes, as the script's materials.gltf), by name, as GLTFLoader reads it.
async function gltfMaterial(url, name) {
    const gltf = await new GLTFLoader().loadAsync(url);
    const index = (gltf.parser.json.materials || []).findIndex((m) => m.name === name);
    if (index < 0) throw new Error(`${url}: no material '${name}'`);
    return gltf.parser.getDependency('material', index);
}

// matremap's framing of a mesh (src/render/mesh.c, mr_camera_frame_mesh), in the asset's world space.
function frameAsset(camera, object, direction, fov) {
    object.updateMatrixWorld(true);
    const box = new THREE.Box3().setFromObject(object, true);
    const centre = box.getCenter(new THREE.Vector3());
    let radius = 0;
    const p = new THREE.Vector3();
    object.traverse((o) => {
        if (!o.isMesh) return;
        const pos = o.geometry.attributes.position;
        for (let i = 0; i < pos.count; i++) {
            p.fromBufferAttribute(pos, i).applyMatrix4(o.matrixWorld);
            radius = Math.max(radius, p.distanceTo(centre));
        }
    });
    const dir = new THREE.Vector3(...direction).normalize();
    const distance = radius / Math.sin(0.9 * 0.5 * fov * Math.PI / 180);
    camera.position.copy(centre).addScaledVector(dir, distance);
    camera.near = 0.01 * distance;
    camera.far = 10 * distance;
    camera.lookAt(centre);
}

window.renderClientJob = async (job) => {
    const started = performance.now();
    const size = job.size, ss = job.supersample, big = size * ss;
    if (!renderer) {
        renderer = new THREE.WebGPURenderer({ antialias: false, alpha: true, forceWebGL: true });
        renderer.setPixelRatio(1);
        renderer.setSize(16, 16);
        renderer.toneMapping = THREE.NoToneMapping;
        await renderer.init();
    }
    const report = { warnings: [], errors: [] };
    // format gltf: the export's source as GLTFLoader reads it (a mesh: the asset's own materials, null here)
    let material = null;
    if (job.format === 'mtlx') material = await mtlxMaterial(job.doc, job.material, report, job.uvSpace);
    else if (job.format === 'usda') material = await usdaMaterial(job.doc, job.material, report);
    else if (!job.mesh) material = await gltfMaterial(job.doc, job.material);
    report.material = material ? material.type : 'the asset\'s own (GLTFLoader)';
    const scene = new THREE.Scene();
    const env = await environment(job.env, job.envMean);
    scene.environment = env.texture;
    scene.environmentRotation.set(0, job.envRotation, 0);
    const camera = new THREE.PerspectiveCamera(job.fov, 1, 0.1, 100);
    let object;
    if (job.mesh) {
        const gltf = await new GLTFLoader().loadAsync(job.mesh);
        object = gltf.scene;
        object.traverse((o) => {
            if (!o.isMesh || !material) return;
            const uv = o.geometry.attributes.uv;
            if (uv && !job.noUvFlip) {
                for (let i = 0; i < uv.count; i++) uv.setY(i, 1 - uv.getY(i));
                uv.needsUpdate = true;
            }
            o.material = material;
        });
        frameAsset(camera, object, job.cameraDirection, job.fov);
    } else {
        object = new THREE.Mesh(new THREE.SphereGeometry(1, 256, 128), material);
        camera.position.set(0, 0, 4);
        camera.lookAt(0, 0, 0);
    }
    camera.updateProjectionMatrix();
    scene.add(object);
    const target = new THREE.RenderTarget(big, big, { type: THREE.FloatType, samples: 4 });
    renderer.setRenderTarget(target);
    renderer.setClearColor(0x000000, 0);
    renderer.clear();
    renderer.render(scene, camera);
    const pixels = await renderer.readRenderTargetPixelsAsync(target, 0, 0, big, big);
    renderer.setRenderTarget(null);
    target.dispose();
    object.traverse((o) => {
        if (!o.isMesh) return;
        o.geometry.dispose();
        for (const v of Object.values(o.material)) if (v && v.isTexture) v.dispose();
        o.material.dispose();
    });
    // Box filter ss x ss blocks; the WebGL2 backend's row 0 is the bottom row, the output's is the top.
    const out = boxFilter(pixels, size, ss, { flip: !!job.flipRows });
    return {
        pixels: toBase64(out), revision: THREE.REVISION, report, envScale: env.scale, backend:
        renderer.backend.isWebGLBackend ? 'WebGL2' : 'WebGPU', seconds: (performance.now() - started) / 1000,
    };
};
window.viewerReady = true;

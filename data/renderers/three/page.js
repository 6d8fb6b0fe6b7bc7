// The page of matremap's three.js renderer server (server.mjs, docs/renderers.md), run in headless Chromium: one
// WebGLRenderer, scene, sphere mesh, pair of materials and pool of point lights, made once and only updated per
// request. window.renderRequest(request) renders the fit scene of a checked render request (protocol: camera,
// sphere, point lights, a `gltf` or `lambert` material by values) into a float render target at size*s, linear
// radiance with no tone mapping or output encoding over a transparent black clear, and returns the s x s box
// filtered RGBA (alpha = coverage) as base64 of a Float32Array, top row first.
import * as THREE from 'three';
import { boxFilter, toBase64 } from 'matremap/readback.js';

// Segments of the SphereGeometry: its triangles' planes lie within 1 - cos(pi/256 * sqrt(2)) = 1.5e-4 of the radius,
// so the silhouette is within 0.03 px of the true sphere's at 512^2 in the fit scene (docs/renderers.md).
const WIDTH_SEGMENTS = 256, HEIGHT_SEGMENTS = 128;
// The largest render target strip (pixels): size*s images larger than this render in strips of whole pixel rows.
const STRIP_PIXELS = 1 << 22;

const renderer = new THREE.WebGLRenderer({ antialias: false, alpha: true, powerPreference: 'high-performance' });
renderer.setPixelRatio(1);
renderer.setSize(16, 16);
renderer.toneMapping = THREE.NoToneMapping;
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
renderer.setClearColor(0x000000, 0);
const floatTargets = renderer.extensions.has('EXT_color_buffer_float');
const targetType = floatTargets ? THREE.FloatType : THREE.HalfFloatType;

const scene = new THREE.Scene(); // no background, no environment: only the point lights light the sphere
const camera = new THREE.PerspectiveCamera(35, 1, 0.1, 10);
const materials = {
    gltf: new THREE.MeshPhysicalMaterial({ side: THREE.FrontSide }),
    // BRDF_Lambert (common.glsl.js) is diffuseColor / pi and RE_Direct_Lambert adds irradiance * BRDF_Lambert:
    // matremap's lambert, f = albedo / pi, with no Fresnel weight (docs/renderers.md).
    lambert: new THREE.MeshLambertMaterial({ side: THREE.FrontSide }),
};
const sphere = new THREE.Mesh(new THREE.SphereGeometry(1, WIDTH_SEGMENTS, HEIGHT_SEGMENTS), materials.gltf);
scene.add(sphere);
const lights = [];
const targets = new Map(); // "WxH" -> render target, kept between requests (up to 8)

function linear(color, rgb) {
    return color.setRGB(rgb[0], rgb[1], rgb[2], THREE.LinearSRGBColorSpace);
}

function setMaterial(material) {
    const v = material.values;
    if (material.model === 'lambert') {
        linear(materials.lambert.color, v.albedo);
        sphere.material = materials.lambert;
        return;
    }
    const m = materials.gltf;
    linear(m.color, v.base_color);
    m.metalness = v.metallic;
    m.roughness = v.roughness;
    m.specularIntensity = v.specular;
    linear(m.specularColor, v.specular_color);
    m.ior = v.ior;
    sphere.material = m;
}

function setLights(list) {
    while (lights.length < list.length) {
        const light = new THREE.PointLight(0xffffff, 1, 0, 2); // distance 0 (no cut-off), decay 2: I cos / d^2
        lights.push(light);
        scene.add(light);
    }
    lights.forEach((light, k) => {
        light.visible = k < list.length;
        if (!light.visible) return;
        const { position, intensity } = list[k];
        const peak = Math.max(...intensity);
        light.position.fromArray(position);
        light.intensity = peak; // candela: three's physical units, the request's W/sr
        if (peak > 0) linear(light.color, intensity.map((i) => i / peak));
        else light.color.setRGB(0, 0, 0);
    });
}

function setCamera(c, sph) {
    const position = new THREE.Vector3().fromArray(c.position);
    const distance = position.distanceTo(new THREE.Vector3().fromArray(sph.center));
    camera.fov = c.fov_y;
    camera.aspect = 1;
    camera.near = Math.max(1e-4 * distance, 0.5 * (distance - sph.radius));
    camera.far = 2 * (distance + sph.radius);
    camera.position.copy(position);
    camera.up.fromArray(c.up);
    camera.lookAt(new THREE.Vector3().fromArray(c.target));
}

function target(width, height) {
    const key = `${width}x${height}`;
    if (!targets.has(key)) {
        if (targets.size >= 8) { // a server that sees many sizes keeps the last few targets, not all
            for (const t of targets.values()) t.dispose();
            targets.clear();
        }
        targets.set(key, new THREE.WebGLRenderTarget(width, height, { type: targetType, depthBuffer: true }));
    }
    return targets.get(key);
}

window.renderRequest = (request) => {
    const size = request.size, ss = request.supersample, big = size * ss;
    setMaterial(request.material);
    setLights(request.lights);
    setCamera(request.camera, request.sphere);
    sphere.position.fromArray(request.sphere.center);
    sphere.scale.setScalar(request.sphere.radius);
    // Strips of whole output rows, top first; each a view offset of the big x big image.
    const rowsPerStrip = Math.max(1, Math.min(size, Math.floor(STRIP_PIXELS / (big * big / size))));
    const out = new Float32Array(size * size * 4);
    for (let row0 = 0; row0 < size; row0 += rowsPerStrip) {
        const rows = Math.min(rowsPerStrip, size - row0);
        const t = target(big, rows * ss);
        if (rows === size) camera.clearViewOffset();
        else camera.setViewOffset(big, big, 0, row0 * ss, big, rows * ss);
        camera.updateProjectionMatrix();
        renderer.setRenderTarget(t);
        renderer.clear();
        renderer.render(scene, camera);
        const pixels = new Float32Array(big * rows * ss * 4);
        renderer.readRenderTargetPixels(t, 0, 0, big, rows * ss, pixels);
        boxFilter(pixels, size, ss, { row0, rows, out });
    }
    renderer.setRenderTarget(null);
    return toBase64(out);
};

window.rendererInfo = {
    revision: THREE.REVISION, targetType: floatTargets ? 'FloatType' : 'HalfFloatType',
    maxTextureSize: renderer.capabilities.maxTextureSize,
};
window.serverReady = true;

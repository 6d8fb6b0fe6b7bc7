// matremap's three.js renderer server (docs/renderers.md, "three.js adapter"): speaks the renderer-server protocol
// on stdin/stdout, one JSON request a line, "@matremap ..." answers. Usage: node server.mjs (env MATREMAP_CHROMIUM:
// the browser, default Debian's chromium). One headless Chromium and one page (page.js) live as long as the
// process; each render only updates the page's material, lights, camera and size. Messages go to stderr.
import { chromium } from 'playwright-core';
import { readFile, writeFile } from 'node:fs/promises';
import { createInterface } from 'node:readline';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { launch, serve } from './page_host.mjs';

const here = dirname(fileURLToPath(import.meta.url));

// The models this server renders by values: matremap's parameters (`matremap models NAME`), each
// [channels, default, min, max].
const MODELS = {
    gltf: {
        base_color: [3, 1, 0, 1], metallic: [1, 1, 0, 1], roughness: [1, 1, 0.01, 1], specular: [1, 1, 0, 1],
        specular_color: [3, 1, 0, 25], ior: [1, 1.5, 1, 5],
    },
    lambert: { albedo: [3, 0.5, 0, 1] },
};
const COMPONENTS = ['full'];

function say(line) {
    process.stdout.write(`@matremap ${line}\n`);
}

const limits = { maxTextureSize: 4096 }; // the page's, once it is loaded
class RequestError extends Error {}
const fail = (message) => { throw new RequestError(message); };
const finite = (x) => typeof x === 'number' && Number.isFinite(x);
// A value as the request had it (JSON.parse reads 1e999 as Infinity, which JSON.stringify would print as null).
const show = (value) => JSON.stringify(value, (k, x) => (typeof x === 'number' && !Number.isFinite(x) ? `${x}` : x))
    .replace(/"(-?Infinity|NaN)"/g, '$1');

function vector(value, name, length = 3) {
    if (!Array.isArray(value) || value.length !== length || !value.every(finite)) {
        fail(`${name} must be ${length} finite numbers, not ${show(value)}`);
    }
    return value;
}

function number(value, name, min, max, { integer = false, open = false } = {}) {
    if (!finite(value) || (integer && !Number.isInteger(value))) {
        fail(`${name} must be a finite ${integer ? 'integer' : 'number'}, not ${show(value)}`);
    }
    if (value < min || value > max || (open && (value === min || value === max))) {
        fail(`${name} ${value} is outside ${open ? '(' : '['}${min}, ${max}${open ? ')' : ']'}`);
    }
    return value;
}

// A model's values: every parameter (the request's or the default), RGB ones as triples (one number = grey).
function materialValues(material) {
    if (material === null || typeof material !== 'object') fail('material must be an object');
    if ('blend' in material) fail('material: three renders no .blend materials (no materials=blend)');
    const params = MODELS[material.model];
    if (!params) {
        fail(`unknown model ${JSON.stringify(material.model)} (three renders: ${Object.keys(MODELS).join(', ')})`);
    }
    const given = material.values ?? {};
    if (given === null || typeof given !== 'object' || Array.isArray(given)) fail('material.values must be an object');
    for (const name of Object.keys(given)) {
        if (!(name in params)) {
            fail(`model ${material.model} has no parameter '${name}' (it has: ${Object.keys(params).join(', ')})`);
        }
    }
    const values = {};
    for (const [name, [channels, fallback, min, max]] of Object.entries(params)) {
        let v = name in given ? given[name] : fallback;
        const list = Array.isArray(v) ? v : [v];
        if (list.length !== 1 && list.length !== channels) {
            fail(`${material.model} ${name} takes ${channels === 1 ? '1 value' : `1 or ${channels} values`}, ` +
                 `not ${list.length}`);
        }
        list.forEach((x, c) => number(x, `${material.model} ${name}${list.length > 1 ? `[${c}]` : ''}`, min, max));
        values[name] = channels === 1 ? list[0] : (list.length === 1 ? [list[0], list[0], list[0]] : list);
    }
    return { model: material.model, values };
}

// The page's job for a render request, every field checked; the output files to write.
function renderJob(r) {
    const size = number(r.size, 'size', 1, 16384, { integer: true });
    const samples = number(r.samples ?? 1, 'samples', 1, 1 << 20, { integer: true });
    const supersample = Math.min(8, Math.max(1, Math.floor(Math.sqrt(samples))));
    if (size * supersample > limits.maxTextureSize) {
        fail(`size ${size} x ${supersample} sub-pixels exceeds the ${limits.maxTextureSize}-pixel render target limit`);
    }
    const c = r.camera ?? fail('camera is missing');
    const camera = {
        position: vector(c.position, 'camera.position'), target: vector(c.target, 'camera.target'),
        up: vector(c.up ?? [0, 1, 0], 'camera.up'), fov_y: number(c.fov_y, 'camera.fov_y', 0, 180, { open: true }),
    };
    const view = camera.target.map((t, k) => t - camera.position[k]);
    const cross = [1, 2, 0].map((i, k) => view[i] * camera.up[(k + 2) % 3] - view[(k + 2) % 3] * camera.up[i]);
    if (Math.hypot(...cross) <= 1e-9 * Math.hypot(...view) * Math.hypot(...camera.up)) {
        fail('camera: position equals target, or up is parallel to the view direction');
    }
    const s = r.sphere ?? { center: [0, 0, 0], radius: 1 };
    const sphere = { center: vector(s.center, 'sphere.center'),
                     radius: number(s.radius, 'sphere.radius', 0, Infinity, { open: true }) };
    if (!Array.isArray(r.lights)) fail('lights must be an array');
    const lights = r.lights.map((l, k) => ({
        position: vector(l?.position, `lights[${k}].position`),
        intensity: finite(l?.intensity) ? [l.intensity, l.intensity, l.intensity]
            : vector(l?.intensity, `lights[${k}].intensity`),
    }));
    lights.forEach((l, k) => l.intensity.forEach((i) => i >= 0 || fail(`lights[${k}].intensity ${i} is negative`)));
    const material = materialValues(r.material);
    const components = r.components ?? ['full'];
    if (!Array.isArray(components) || components.length === 0) fail('components must be a non-empty array');
    for (const name of components) {
        if (!COMPONENTS.includes(name)) {
            fail(`component ${JSON.stringify(name)} is not supported by three (components=${COMPONENTS.join(',')})`);
        }
    }
    if (typeof r.output !== 'string' || !r.output.startsWith('/')) fail('output must be an absolute path prefix');
    return { job: { size, supersample, camera, sphere, lights, material }, files: components.map(
        (name) => `${r.output}.${name}.f32`) };
}

async function render(page, request) {
    const { job, files } = renderJob(request);
    const base64 = await page.evaluate((j) => window.renderRequest(j), job);
    const pixels = Buffer.from(base64, 'base64'); // little-endian float32 RGBA, as the protocol's files
    for (const file of files) {
        try {
            await writeFile(file, pixels);
        } catch (e) {
            fail(`cannot write ${file}: ${e.code || e.message}`);
        }
    }
}

async function main() {
    const started = performance.now();
    const { version } = JSON.parse(await readFile(join(here, 'node_modules/three/package.json'), 'utf8'));
    const host = await serve({
        root: here, page: 'page.js', packages: ['three'],
        importmap: () => ({ three: '/modules/three/build/three.module.js' }),
    });
    const browser = await launch(chromium, process.env.MATREMAP_CHROMIUM || '/usr/bin/chromium');
    const page = await browser.newPage();
    page.on('console', (m) => { // SwiftShader's "GPU stall due to ReadPixels" is every render's: not news
        if ((m.type() === 'error' || m.type() === 'warning') && !m.text().includes('GPU stall due to ReadPixels')) {
            process.stderr.write(`three: page ${m.type()}: ${m.text()}\n`);
        }
    });
    page.on('pageerror', (e) => process.stderr.write(`three: page error: ${e.message}\n`));
    await page.goto(`http://127.0.0.1:${host.port}/`);
    await page.waitForFunction(() => window.serverReady === true, null, { timeout: 60000 });
    // Compile both materials' programs (one point light, the usual scene) before saying ready.
    for (const model of Object.keys(MODELS)) {
        await page.evaluate((j) => window.renderRequest(j), renderJob({
            size: 4, samples: 1, camera: { position: [0, 0, 4], target: [0, 0, 0], up: [0, 1, 0], fov_y: 35 },
            lights: [{ position: [3, 0, 3], intensity: 1 }], material: { model }, output: '/warm-up',
        }).job);
    }
    const info = await page.evaluate(() => window.rendererInfo);
    limits.maxTextureSize = info.maxTextureSize;
    process.stderr.write(`three: r${info.revision} in ${browser.version()}, render targets ${info.targetType}, ` +
                         `max texture ${info.maxTextureSize}; ready in ${((performance.now() - started) / 1000)
                             .toFixed(2)} s\n`);
    say(`ready three ${version} components=${COMPONENTS.join(',')} models=${Object.keys(MODELS).join(',')}`);

    const quit = async (code) => {
        await browser.close().catch(() => {});
        host.close();
        process.exit(code);
    };
    const lines = createInterface({ input: process.stdin, crlfDelay: Infinity });
    for await (const line of lines) {
        if (line.trim() === '') continue;
        let request, id = -1;
        const t0 = performance.now();
        try {
            try {
                request = JSON.parse(line);
            } catch (e) {
                fail(`malformed JSON request: ${e.message}`);
            }
            if (request === null || typeof request !== 'object' || Array.isArray(request)) {
                fail('a request must be a JSON object');
            }
            if (request.op === 'quit') break;
            if (!Number.isInteger(request.id)) fail(`id must be an integer, not ${JSON.stringify(request.id)}`);
            id = request.id;
            if (request.op !== 'render') fail(`unknown op ${JSON.stringify(request.op)} (three answers: render, quit)`);
            await render(page, request);
            say(`ok ${id} ${((performance.now() - t0) / 1000).toFixed(4)}`);
        } catch (e) {
            if (!(e instanceof RequestError)) process.stderr.write(`three: request ${id}: ${e.stack || e}\n`);
            say(`error ${id} ${String(e.message).split('\n')[0]}`);
            if (!(e instanceof RequestError) && (page.isClosed() || !browser.isConnected())) await quit(3);
        }
    }
    await quit(0);
}

main().catch((e) => {
    process.stderr.write(`three: ${e.stack || e}\n`);
    process.exit(3);
});

// Renders the documents of make evaluation-clients (scripts/evaluate-clients.sh, docs/evaluation-clients.md) with
// three.js's MaterialXLoader and USDLoader in headless Chromium (client_page.js).
// Usage: node client_render.mjs JOBS.json
// JOBS.json: {"chromium": "/usr/lib/chromium/chromium", "jobs": [{"format": "mtlx" | "usda" | "gltf", "doc": ABS,
//   "material": NAME, "mesh": null | ABS.gltf, "cameraDirection": [x, y, z], "fov": 35, "env": ABS.hdr,
//   "envMean": 0.5, "envRotation": radians, "flipRows": true, "noUvFlip": false, "out": ABS.exr, "size": 256,
//   "supersample": 2}, ...]} (client_page.js says what each field does).
// Each job's render (linear RGBA) is written as an uncompressed float EXR; one JSON line per job on stdout ({"out",
// "revision", "backend", "report": {"material", "warnings", "errors", "console"}, "env_scale", "seconds"}), the
// loaders' console warnings and errors during the job included. One page for all jobs (it keeps its PMREM
// environments). Exit 0 when every job rendered, 3 otherwise.
import { chromium } from 'playwright-core';
import { createServer } from 'node:http';
import { readFile, writeFile, rename } from 'node:fs/promises';
import { dirname, extname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html', '.json': 'application/json',
                '.gltf': 'model/gltf+json', '.glb': 'model/gltf-binary', '.bin': 'application/octet-stream',
                '.mtlx': 'application/xml', '.usda': 'text/plain', '.png': 'image/png', '.jpg': 'image/jpeg',
                '.jpeg': 'image/jpeg', '.hdr': 'application/octet-stream' };

// One uncompressed scanline EXR, channels A, B, G, R (sorted by name, as OpenEXR stores them), FLOAT.
function exr(width, height, rgba) {
    const parts = [];
    const attr = (name, type, value) => {
        parts.push(Buffer.from(`${name}\0${type}\0`, 'latin1'));
        const size = Buffer.alloc(4);
        size.writeInt32LE(value.length);
        parts.push(size, value);
    };
    const i32 = (...v) => {
        const b = Buffer.alloc(4 * v.length);
        v.forEach((x, k) => b.writeInt32LE(x, 4 * k));
        return b;
    };
    const f32 = (...v) => {
        const b = Buffer.alloc(4 * v.length);
        v.forEach((x, k) => b.writeFloatLE(x, 4 * k));
        return b;
    };
    const channels = [];
    for (const c of ['A', 'B', 'G', 'R']) { // name, pixel type FLOAT, pLinear + reserved, x/y sampling
        channels.push(Buffer.from(`${c}\0`, 'latin1'), i32(2), Buffer.from([0, 0, 0, 0]), i32(1, 1));
    }
    channels.push(Buffer.from([0]));
    parts.push(i32(20000630), i32(2));
    attr('channels', 'chlist', Buffer.concat(channels));
    attr('compression', 'compression', Buffer.from([0]));
    attr('dataWindow', 'box2i', i32(0, 0, width - 1, height - 1));
    attr('displayWindow', 'box2i', i32(0, 0, width - 1, height - 1));
    attr('lineOrder', 'lineOrder', Buffer.from([0]));
    attr('pixelAspectRatio', 'float', f32(1));
    attr('screenWindowCenter', 'v2f', f32(0, 0));
    attr('screenWindowWidth', 'float', f32(1));
    parts.push(Buffer.from([0]));
    const header = Buffer.concat(parts);
    const lineBytes = 8 + 4 * 4 * width;
    const offsets = Buffer.alloc(8 * height);
    for (let y = 0; y < height; y++) {
        offsets.writeBigUInt64LE(BigInt(header.length + 8 * height + y * lineBytes), 8 * y);
    }
    const lines = Buffer.alloc(lineBytes * height);
    for (let y = 0; y < height; y++) {
        let p = y * lineBytes;
        lines.writeInt32LE(y, p);
        lines.writeInt32LE(4 * 4 * width, p + 4);
        p += 8;
        for (const c of [3, 2, 1, 0]) {
            for (let x = 0; x < width; x++, p += 4) lines.writeFloatLE(rgba[4 * (y * width + x) + c], p);
        }
    }
    return Buffer.concat([header, offsets, lines]);
}

async function main() {
    const spec = JSON.parse(await readFile(process.argv[2], 'utf8'));
    const modules = resolve(here, 'node_modules');
    // Everything the page may load: this folder, three.js, and the folders of the jobs' files (by absolute path).
    const allowed = new Set(spec.jobs.flatMap((j) => [j.env, j.doc, ...(j.mesh ? [j.mesh] : [])])
        .map((p) => dirname(resolve(p))));
    const server = createServer(async (req, res) => {
        try {
            const url = decodeURIComponent(new URL(req.url, 'http://x').pathname);
            let file = null;
            if (url === '/' || url === '/index.html') {
                res.writeHead(200, { 'content-type': 'text/html' });
                const imports = { three: '/modules/three/build/three.webgpu.js',
                                  'three/webgpu': '/modules/three/build/three.webgpu.js',
                                  'three/tsl': '/modules/three/build/three.tsl.js',
                                  'three/addons/': '/modules/three/examples/jsm/' };
                res.end(`<!doctype html><html><body><script type="importmap">${JSON.stringify({ imports })}` +
                        `</script><script type="module" src="/client_page.js"></script></body></html>`);
                return;
            }
            if (url === '/client_page.js') file = join(here, 'client_page.js');
            else if (url.startsWith('/modules/three/')) file = join(modules, url.slice('/modules/'.length));
            else if (url.startsWith('/files/')) {
                file = resolve(url.slice('/files'.length));
                let ok = false;
                for (const a of allowed) if (file.startsWith(a + '/')) ok = true;
                if (!ok) file = null;
            }
            if (!file || file.includes('..')) { res.writeHead(404); res.end(); return; }
            const body = await readFile(file);
            res.writeHead(200, { 'content-type': types[extname(file).toLowerCase()] || 'application/octet-stream' });
            res.end(body);
        } catch (e) {
            res.writeHead(404);
            res.end(String(e));
        }
    });
    await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
    const port = server.address().port;
    const browser = await chromium.launch({
        executablePath: spec.chromium || '/usr/lib/chromium/chromium',
        args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
    });
    let failed = 0;
    try {
        const page = await browser.newPage();
        let console_ = [];
        page.on('console', (m) => {
            const kind = m.type();
            if (kind === 'error' || kind === 'warning') {
                console_.push(`${kind}: ${m.text()}`);
                process.stderr.write(`[page] ${kind}: ${m.text()}\n`);
            }
        });
        page.on('pageerror', (e) => process.stderr.write(`[page] page error: ${e.message}\n`));
        await page.goto(`http://127.0.0.1:${port}/`);
        await page.waitForFunction(() => window.viewerReady === true, null, { timeout: 60000 });
        for (const job of spec.jobs) {
            console_ = [];
            try {
                const r = await page.evaluate((j) => window.renderClientJob(j), {
                    ...job, doc: `/files${resolve(job.doc)}`, env: `/files${resolve(job.env)}`,
                    mesh: job.mesh ? `/files${resolve(job.mesh)}` : null,
                });
                const pixels = new Float32Array(new Uint8Array(Buffer.from(r.pixels, 'base64')).buffer);
                await writeFile(job.out + '.tmp', exr(job.size, job.size, pixels));
                await rename(job.out + '.tmp', job.out);
                console.log(JSON.stringify({ out: job.out, revision: r.revision, backend: r.backend,
                                             report: { ...r.report, console: console_ }, env_scale: r.envScale,
                                             seconds: r.seconds }));
            } catch (e) {
                failed++;
                process.stderr.write(`client_render: ${job.doc} '${job.material}': ${e.message}\n`);
            }
        }
    } finally {
        await browser.close();
        server.close();
    }
    process.exit(failed ? 3 : 0);
}

main().catch((e) => { process.stderr.write(`client_render: ${e.stack || e}\n`); process.exit(3); });

// Renders glTF assets with three.js in headless Chromium (make evaluation-viewers; docs/evaluation.md, "What
// viewers show"). Usage: node three_render.mjs JOBS.json
// JOBS.json: {"chromium": "/usr/lib/chromium/chromium", "jobs": [{"three": "three" | "three-r146", "gltf": ABS,
//   "env": ABS.hdr, "out": ABS.exr, "size": 384, "supersample": 2, "envMean": 0.5,
//   "view": {"azimuth": deg, "elevation": deg, "fov": deg, "margin": 1.05}}, ...]}
// Each job's render (linear RGBA, see three_page.js) is written as an uncompressed float EXR; one JSON line per
// job on stdout ({"out", "three", "revision", "materials", "seconds"}). Jobs run in order, one page per three.js
// package (the page keeps its PMREM environments between jobs). Exit 0 when every job rendered, 3 otherwise.
import { chromium } from 'playwright-core';
import { createServer } from 'node:http';
import { readFile, writeFile, rename } from 'node:fs/promises';
import { dirname, extname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html', '.json': 'application/json',
                '.gltf': 'model/gltf+json', '.glb': 'model/gltf-binary', '.bin': 'application/octet-stream',
                '.png': 'image/png', '.jpg': 'image/jpeg', '.jpeg': 'image/jpeg', '.hdr': 'application/octet-stream' };

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
    // Everything the page may load: this folder, the two three.js packages, and the jobs' files (by absolute path).
    const allowed = new Set(spec.jobs.flatMap((j) => [j.env, j.gltf]).map((p) => dirname(resolve(p))));
    const server = createServer(async (req, res) => {
        try {
            const url = decodeURIComponent(new URL(req.url, 'http://x').pathname);
            let file = null;
            if (url === '/' || url === '/index.html') {
                res.writeHead(200, { 'content-type': 'text/html' });
                const three = new URL(req.url, 'http://x').searchParams.get('three');
                const imports = { three: `/modules/${three}/build/three.module.js`,
                                  'three/addons/': `/modules/${three}/examples/jsm/` };
                res.end(`<!doctype html><html><body><script type="importmap">${JSON.stringify({ imports })}` +
                        `</script><script type="module" src="/three_page.js"></script></body></html>`);
                return;
            }
            if (url === '/three_page.js') file = join(here, 'three_page.js');
            else if (url.startsWith('/modules/three/') || url.startsWith('/modules/three-r146/'))
                file = join(modules, url.slice('/modules/'.length));
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
        const pages = new Map();
        for (const job of spec.jobs) {
            if (!pages.has(job.three)) {
                const page = await browser.newPage();
                page.on('console', (m) => {
                    const kind = m.type();
                    if (kind === 'error' || kind === 'warning') process.stderr.write(`[${job.three}] ${m.text()}\n`);
                });
                page.on('pageerror', (e) => process.stderr.write(`[${job.three}] page error: ${e.message}\n`));
                await page.goto(`http://127.0.0.1:${port}/?three=${job.three}`);
                await page.waitForFunction(() => window.viewerReady === true, null, { timeout: 60000 });
                pages.set(job.three, page);
            }
            const page = pages.get(job.three);
            try {
                const r = await page.evaluate((j) => window.renderJob(j), {
                    ...job, gltf: `/files${resolve(job.gltf)}`, env: `/files${resolve(job.env)}`,
                });
                const pixels = new Float32Array(new Uint8Array(Buffer.from(r.pixels, 'base64')).buffer);
                await writeFile(job.out + '.tmp', exr(job.size, job.size, pixels));
                await rename(job.out + '.tmp', job.out);
                console.log(JSON.stringify({ out: job.out, three: job.three, revision: r.revision,
                                             materials: r.materials, env_scale: r.envScale, seconds: r.seconds }));
            } catch (e) {
                failed++;
                process.stderr.write(`three_render: ${job.gltf} (${job.three}): ${e.message}\n`);
            }
        }
    } finally {
        await browser.close();
        server.close();
    }
    process.exit(failed ? 3 : 0);
}

main().catch((e) => { process.stderr.write(`three_render: ${e.stack || e}\n`); process.exit(3); });

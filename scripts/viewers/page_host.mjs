// What three_render.mjs (make evaluation-viewers) and client_render.mjs (make evaluation-clients) share: a local
// HTTP server for one page and the files its jobs name, headless Chromium, and the float EXR a render is saved as.
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

/* Serves, on 127.0.0.1 at a free port: "/" (the page: `importmap(searchParams)` as its import map, then the module
 * `page`, a file of this folder), `/<page>`, `/modules/<package>/...` for the node_modules packages named in
 * `packages`, and `/files/<absolute path>` for files inside the folders of `files` (nothing else: 404).
 * Returns { port, close }. */
export async function serve({ page, packages, files, importmap }) {
    const modules = resolve(here, 'node_modules');
    const allowed = new Set(files.map((p) => dirname(resolve(p))));
    const server = createServer(async (req, res) => {
        try {
            const url = new URL(req.url, 'http://x');
            const path = decodeURIComponent(url.pathname);
            let file = null;
            if (path === '/' || path === '/index.html') {
                res.writeHead(200, { 'content-type': 'text/html' });
                res.end(`<!doctype html><html><body><script type="importmap">` +
                        `${JSON.stringify({ imports: importmap(url.searchParams) })}</script>` +
                        `<script type="module" src="/${page}"></script></body></html>`);
                return;
            }
            if (path === `/${page}`) file = join(here, page);
            else if (packages.some((p) => path.startsWith(`/modules/${p}/`))) file = join(modules, path.slice(9));
            else if (path.startsWith('/files/')) {
                file = resolve(path.slice('/files'.length));
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
    return { port: server.address().port, close: () => server.close() };
}

/* Debian's Chromium, headless, with the software WebGL the renders need. */
export function launch(executablePath) {
    return chromium.launch({
        executablePath: executablePath || '/usr/lib/chromium/chromium',
        args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
    });
}

/* A page's render (base64 of size x size linear RGBA floats) written to `out` as a float EXR, atomically. */
export async function writeRender(out, size, base64) {
    const pixels = new Float32Array(new Uint8Array(Buffer.from(base64, 'base64')).buffer);
    await writeFile(out + '.tmp', exr(size, size, pixels));
    await rename(out + '.tmp', out);
}

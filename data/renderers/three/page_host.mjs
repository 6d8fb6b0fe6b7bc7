// What matremap's three.js renderer server (server.mjs) and scripts/viewers (three_render.mjs for make
// evaluation-viewers, client_render.mjs for make evaluation-clients) share: a local HTTP server for one page, its
// packages and the files its jobs name, and headless Chromium. Self-contained (it is installed with server.mjs);
// the caller passes its own playwright-core's `chromium`, so each folder uses the packages it pins.
import { createServer } from 'node:http';
import { readFile } from 'node:fs/promises';
import { dirname, extname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const types = { '.js': 'text/javascript', '.mjs': 'text/javascript', '.html': 'text/html', '.json': 'application/json',
                '.gltf': 'model/gltf+json', '.glb': 'model/gltf-binary', '.bin': 'application/octet-stream',
                '.mtlx': 'application/xml', '.usda': 'text/plain', '.png': 'image/png', '.jpg': 'image/jpeg',
                '.jpeg': 'image/jpeg', '.hdr': 'application/octet-stream' };

/* Serves, on 127.0.0.1 at a free port: "/" (the page: `importmap(searchParams)` plus `matremap/` as its import map,
 * then the module `page`, a file of the folder `root`), `/<page>`, `/modules/<package>/...` for the packages named
 * in `packages` (from root/node_modules), `/host/<name>.js` for this folder's browser modules (readback.js, imported
 * as 'matremap/readback.js') and `/files/<absolute path>` for files inside the folders of `files` (nothing else:
 * 404). Returns { port, close }. */
export async function serve({ root, page, packages, files = [], importmap }) {
    const modules = resolve(root, 'node_modules');
    const allowed = new Set(files.map((p) => dirname(resolve(p))));
    const server = createServer(async (req, res) => {
        try {
            const url = new URL(req.url, 'http://x');
            const path = decodeURIComponent(url.pathname);
            let file = null;
            if (path === '/favicon.ico') { res.writeHead(204); res.end(); return; }
            if (path === '/' || path === '/index.html') {
                res.writeHead(200, { 'content-type': 'text/html' });
                res.end(`<!doctype html><html><body><script type="importmap">` +
                        `${JSON.stringify({ imports: { ...importmap(url.searchParams), 'matremap/': '/host/' } })}</script>` +
                        `<script type="module" src="/${page}"></script></body></html>`);
                return;
            }
            if (path === `/${page}`) file = join(root, page);
            else if (/^\/host\/[a-z_]+\.js$/.test(path)) file = join(here, path.slice(6));
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

/* Debian's Chromium (the binary /usr/bin/chromium wraps unless `executablePath` says otherwise), headless, with the
 * software WebGL the renders need, launched by the caller's playwright-core `chromium`. */
export function launch(chromium, executablePath) {
    return chromium.launch({
        executablePath: executablePath || '/usr/lib/chromium/chromium',
        args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
    });
}


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
import { readFile } from 'node:fs/promises';
import { resolve } from 'node:path';
import { launch, serve, writeRender } from './page_host.mjs';

async function main() {
    const spec = JSON.parse(await readFile(process.argv[2], 'utf8'));
    // Everything the page may load: this folder, three.js, and the folders of the jobs' files (by absolute path).
    const host = await serve({
        page: 'client_page.js', packages: ['three'],
        files: spec.jobs.flatMap((j) => [j.env, j.doc, ...(j.mesh ? [j.mesh] : [])]),
        importmap: () => ({ three: '/modules/three/build/three.webgpu.js',
                            'three/webgpu': '/modules/three/build/three.webgpu.js',
                            'three/tsl': '/modules/three/build/three.tsl.js',
                            'three/addons/': '/modules/three/examples/jsm/' }),
    });
    const port = host.port;
    const browser = await launch(spec.chromium);
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
                await writeRender(job.out, job.size, r.pixels);
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
        host.close();
    }
    process.exit(failed ? 3 : 0);
}

main().catch((e) => { process.stderr.write(`client_render: ${e.stack || e}\n`); process.exit(3); });

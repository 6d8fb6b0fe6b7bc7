// Renders glTF assets with three.js in headless Chromium (make evaluation-viewers; docs/evaluation.md, "What
// viewers show"). Usage: node three_render.mjs JOBS.json
// JOBS.json: {"chromium": "/usr/lib/chromium/chromium", "jobs": [{"three": "three" | "three-r146", "gltf": ABS,
//   "env": ABS.hdr, "out": ABS.exr, "size": 384, "supersample": 2, "envMean": 0.5,
//   "view": {"azimuth": deg, "elevation": deg, "fov": deg, "margin": 1.05}}, ...]}
// Each job's render (linear RGBA, see three_page.js) is written as an uncompressed float EXR; one JSON line per
// job on stdout ({"out", "three", "revision", "materials", "seconds"}). Jobs run in order, one page per three.js
// package (the page keeps its PMREM environments between jobs). Exit 0 when every job rendered, 3 otherwise.
import { readFile } from 'node:fs/promises';
import { resolve } from 'node:path';
import { launch, serve, writeRender } from './page_host.mjs';

async function main() {
    const spec = JSON.parse(await readFile(process.argv[2], 'utf8'));
    // Everything the page may load: this folder, three.js, and the folders of the jobs' files (by absolute path).
    const host = await serve({
        page: 'three_page.js', packages: ['three', 'three-r146'], files: spec.jobs.flatMap((j) => [j.env, j.gltf]),
        importmap: (q) => ({ three: `/modules/${q.get('three')}/build/three.module.js`,
                             'three/addons/': `/modules/${q.get('three')}/examples/jsm/` }),
    });
    const port = host.port;
    const browser = await launch(spec.chromium);
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
                await writeRender(job.out, job.size, r.pixels);
                console.log(JSON.stringify({ out: job.out, three: job.three, revision: r.revision,
                                             materials: r.materials, env_scale: r.envScale, seconds: r.seconds }));
            } catch (e) {
                failed++;
                process.stderr.write(`three_render: ${job.gltf} (${job.three}): ${e.message}\n`);
            }
        }
    } finally {
        await browser.close();
        host.close();
    }
    process.exit(failed ? 3 : 0);
}

main().catch((e) => { process.stderr.write(`three_render: ${e.stack || e}\n`); process.exit(3); });

// What three_render.mjs (make evaluation-viewers) and client_render.mjs (make evaluation-clients) share: the page
// host and Chromium of data/renderers/three/page_host.mjs (serving this folder's pages and packages), and the float
// EXR a render is saved as.
import { chromium } from 'playwright-core';
import { writeFile, rename } from 'node:fs/promises';
import { dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as host from '../../data/renderers/three/page_host.mjs';

const here = dirname(fileURLToPath(import.meta.url));

export const serve = (options) => host.serve({ root: here, ...options });
export const launch = (executablePath) => host.launch(chromium, executablePath);

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

/* A page's render (base64 of size x size linear RGBA floats) written to `out` as a float EXR, atomically. */
export async function writeRender(out, size, base64) {
    const pixels = new Float32Array(new Uint8Array(Buffer.from(base64, 'base64')).buffer);
    await writeFile(out + '.tmp', exr(size, size, pixels));
    await rename(out + '.tmp', out);
}

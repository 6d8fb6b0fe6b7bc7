// Browser-side helpers the pages served by page_host.mjs share (imported as 'matremap/readback.js'): the server's
// page (page.js) and scripts/viewers' three_page.js and client_page.js read a float render target back, box-filter
// it and hand it to node as base64.

/* Averages ss x ss blocks of `pixels` (RGBA floats, size*ss columns, rows*ss sub-rows) into rows `row0` ..
 * `row0 + rows - 1` of `out` (size x size RGBA, top row first). flip: the sub-rows are bottom-first (WebGL's
 * readPixels), so the block of sub-rows 0 .. ss-1 is output row row0 + rows - 1. Returns out. */
export function boxFilter(pixels, size, ss, { flip = true, row0 = 0, rows = size, out = null } = {}) {
    const result = out || new Float32Array(size * size * 4);
    const big = size * ss;
    const norm = 1 / (ss * ss);
    for (let y = 0; y < rows; y++) {
        const row = row0 + (flip ? rows - 1 - y : y);
        for (let x = 0; x < size; x++) {
            const o = 4 * (row * size + x);
            for (let dy = 0; dy < ss; dy++) {
                for (let dx = 0; dx < ss; dx++) {
                    const i = 4 * ((y * ss + dy) * big + x * ss + dx);
                    for (let c = 0; c < 4; c++) result[o + c] += pixels[i + c] * norm;
                }
            }
        }
    }
    return result;
}

/* A typed array's bytes as base64 (page.evaluate returns strings cheaply). */
export function toBase64(array) {
    const bytes = new Uint8Array(array.buffer, array.byteOffset, array.byteLength);
    let binary = '';
    for (let i = 0; i < bytes.length; i += 0x8000) {
        binary += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    }
    return btoa(binary);
}

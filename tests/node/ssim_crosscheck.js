// ssim_crosscheck.js — the independent side of tests/ssim_crosscheck.sh.
//
//   node ssim_crosscheck.js generate DIR   writes the test images (8-bit greyscale PNGs) and DIR/pairs.txt
//   node ssim_crosscheck.js ssim DIR       prints "NAME MSSIM" for every pair in DIR/pairs.txt
//
// The images are generated here, in JavaScript, and encoded by pngjs, so neither the pixels nor the PNG
// encoder come from matremap; the JPEG-degraded copy is made by the shell script with oiiotool.
//
// SSIM: ssim.js 3.5.0 with {ssim: 'original'}, its line-by-line port of Wang's ssim.m (11x11 Gaussian,
// sigma 1.5, K1 0.01, K2 0.03, L = 2^8 - 1, filter2 'valid'). Its default 'weber' variant is a different
// formula. Downsampling is disabled ({downsample: false}) except for pairs marked "matlab", which use its
// 'original' downsampling (maxSize 256), i.e. ssim.m's rule.
//
// Grey conversion in ssim.js (src/matlab/rgb2gray.ts): the default rgb2grayVersion 'integer' computes
// (77 R + 150 G + 29 B + 128) >> 8, and 'original' computes trunc(0.29894 R + 0.58704 G + 0.11402 B + 0.5);
// both round to whole 8-bit levels. matremap's luma is BT.601 0.299 R' + 0.587 G' + 0.114 B' kept in floating
// point (src/metrics/metrics.h), so on colour images the two would compare slightly different grey images.
// Every image here is therefore greyscale (R = G = B = v), where both versions give exactly v
// (77 + 150 + 29 = 256) and so does BT.601 (the weights sum to 1): both sides see identical grey values.
'use strict';

const fs = require('fs');
const path = require('path');
const { PNG } = require('pngjs');
const { ssim } = require('ssim.js');

// xorshift32: deterministic noise, no dependency on Math.random
function rng(seed) {
  let s = seed >>> 0 || 1;
  return () => {
    s ^= s << 13; s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5; s >>>= 0;
    return s / 4294967296;
  };
}

const clamp8 = (v) => Math.max(0, Math.min(255, Math.round(v)));

// A lit sphere on a graded background, in 8-bit display values, plus uniform noise of +-noise/2 levels.
function sphere(w, h, noise, seed) {
  const rand = rng(seed);
  const out = new Uint8Array(w * h);
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const u = ((x + 0.5) / w) * 2 - 1, v = ((y + 0.5) / h) * 2 - 1;
      const r2 = u * u + v * v;
      let value = 20 + 40 * (u + 1) + 15 * Math.sin(7 * v);
      if (r2 < 0.7) {
        const nz = Math.sqrt(1 - r2 / 0.7);
        const diffuse = Math.max(0, 0.35 * u - 0.45 * v + 0.8 * nz);
        const hx = u + 0.25, hy = v + 0.3;
        value = 25 + 170 * diffuse + 140 * Math.exp(-(hx * hx + hy * hy) / 0.012);
      }
      out[y * w + x] = clamp8(value + noise * (rand() - 0.5));
    }
  }
  return { w, h, data: out };
}

function map(img, f) {
  const data = new Uint8Array(img.data.length);
  for (let i = 0; i < data.length; i++) data[i] = clamp8(f(img.data[i]));
  return { w: img.w, h: img.h, data };
}

// Separable Gaussian blur (sigma 1.5, radius 4), edges clamped.
function blur(img) {
  const { w, h } = img;
  const taps = [];
  for (let k = -4; k <= 4; k++) taps.push(Math.exp(-(k * k) / (2 * 1.5 * 1.5)));
  const norm = taps.reduce((a, b) => a + b, 0);
  const tmp = new Float64Array(w * h);
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++) {
      let s = 0;
      for (let k = -4; k <= 4; k++) s += taps[k + 4] * img.data[y * w + Math.min(w - 1, Math.max(0, x + k))];
      tmp[y * w + x] = s / norm;
    }
  const data = new Uint8Array(w * h);
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++) {
      let s = 0;
      for (let k = -4; k <= 4; k++) s += taps[k + 4] * tmp[Math.min(h - 1, Math.max(0, y + k)) * w + x];
      data[y * w + x] = clamp8(s / norm);
    }
  return { w, h, data };
}

// Shift content right and down by (dx, dy), edges repeated.
function shift(img, dx, dy) {
  const { w, h } = img;
  const data = new Uint8Array(w * h);
  for (let y = 0; y < h; y++)
    for (let x = 0; x < w; x++)
      data[y * w + x] = img.data[Math.max(0, y - dy) * w + Math.max(0, x - dx)];
  return { w, h, data };
}

function writeGreyPng(file, img) {
  const png = new PNG({ width: img.w, height: img.h, colorType: 0, inputColorType: 0, bitDepth: 8 });
  png.data = Buffer.from(img.data);
  fs.writeFileSync(file, PNG.sync.write(png, { colorType: 0, inputColorType: 0, bitDepth: 8 }));
}

function readPng(file) {
  const png = PNG.sync.read(fs.readFileSync(file)); // always RGBA, 8 bits per sample
  for (let i = 0; i < png.data.length; i += 4) {
    if (png.data[i] !== png.data[i + 1] || png.data[i] !== png.data[i + 2])
      throw new Error(`${file}: pixel ${i / 4} is not grey; the cross-check needs R = G = B (see the header)`);
  }
  return { width: png.width, height: png.height, data: new Uint8ClampedArray(png.data) };
}

// f(value) with a fresh noise source per image: v + amplitude * (uniform - 1/2)
function noisy(img, amplitude, seed) {
  const rand = rng(seed);
  return map(img, (v) => v + amplitude * (rand() - 0.5));
}

function generate(dir) {
  const base = sphere(300, 240, 12, 1);
  const images = {
    'base.png': base,
    'noisy.png': noisy(base, 60, 7),
    'blurred.png': blur(base),
    'shifted.png': shift(base, 2, 1),
    'contrast.png': map(base, (v) => 0.7 * v + 40),
    'other.png': sphere(300, 240, 40, 99),
    // ~3x the size: ssim.m's rule downsamples by round(780 / 256) = 3
    'big.png': sphere(800, 780, 12, 5),
    'big_noisy.png': noisy(sphere(800, 780, 12, 5), 50, 3),
    // round(520 / 256) = 2: an even factor (see the note in ssim_crosscheck.sh)
    'even.png': sphere(520, 520, 12, 11),
    'even_noisy.png': noisy(sphere(520, 520, 12, 11), 50, 5),
  };
  for (const [name, img] of Object.entries(images)) writeGreyPng(path.join(dir, name), img);
  // NAME A B MODE: MODE full = no downsampling on either side, matlab = ssim.m's downsampling on both,
  // note = compared for information only (not a pass/fail check)
  const pairs = [
    'identical base.png base.png full',
    'noise base.png noisy.png full',
    'blur base.png blurred.png full',
    'jpeg base.png jpeg.png full', // jpeg.png is made by the shell script (oiiotool)
    'shift base.png shifted.png full',
    'contrast base.png contrast.png full',
    'unrelated base.png other.png full',
    'noise_vs_blur noisy.png blurred.png full',
    'big_full big.png big_noisy.png full',
    'big_matlab big.png big_noisy.png matlab',
    'even_matlab even.png even_noisy.png note',
  ];
  fs.writeFileSync(path.join(dir, 'pairs.txt'), pairs.join('\n') + '\n');
}

function compareAll(dir) {
  const lines = fs.readFileSync(path.join(dir, 'pairs.txt'), 'utf8').trim().split('\n');
  for (const line of lines) {
    const [name, a, b, mode] = line.split(/\s+/);
    const options = { ssim: 'original', downsample: mode === 'full' ? false : 'original' };
    const result = ssim(readPng(path.join(dir, a)), readPng(path.join(dir, b)), options);
    process.stdout.write(`${name} ${result.mssim.toPrecision(17)}\n`);
  }
}

const [command, dir] = process.argv.slice(2);
if (command === 'generate' && dir) generate(dir);
else if (command === 'ssim' && dir) compareAll(dir);
else {
  process.stderr.write('usage: node ssim_crosscheck.js generate|ssim DIR\n');
  process.exit(2);
}

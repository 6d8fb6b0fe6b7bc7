// What three.js's USDLoader makes of the materials of a .usda layer, in node (no browser: USDAParser and
// USDComposer need no DOM for constant inputs; images are not decoded). Usage:
//   node usd_materials.mjs LAYER.usda NAME...
// For each NAME, the layer's text is parsed with a probe prim appended (a one-triangle Mesh bound to
// </Materials/NAME>, as client_page.js does) and the MeshPhysicalMaterial USDComposer builds for it is printed as
// one JSON line: {"name", "type", "color", "metalness", "roughness", "ior", "specularColor", "specularIntensity",
// "clearcoat", "clearcoatRoughness", "maps": [...]} (tests/client_docs.sh). Exit 0, or 2 when a material is missing.
import { readFileSync } from 'node:fs';
import { dirname } from 'node:path';
import { USDLoader } from 'three/addons/loaders/USDLoader.js';

const [layer, ...names] = process.argv.slice(2);
const text = readFileSync(layer, 'utf8');
let status = 0;
for (const name of names) {
    // USDComposer gives a default material for a binding to nothing: look for the Material itself first.
    if (!text.includes(`def Material "${name}"`)) {
        process.stderr.write(`usd_materials: ${layer}: no material '${name}'\n`);
        status = 2;
        continue;
    }
    const probe = `\ndef Mesh "MatremapClientProbe" (\n    prepend apiSchemas = ["MaterialBindingAPI"]\n)\n{\n` +
        '    int[] faceVertexCounts = [3]\n    int[] faceVertexIndices = [0, 1, 2]\n' +
        '    point3f[] points = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]\n' +
        `    rel material:binding = </Materials/${name}>\n}\n`;
    const group = new USDLoader().parse(text + probe, dirname(layer) + '/');
    let m = null;
    group.traverse((o) => { if (o.isMesh && o.name === 'MatremapClientProbe') m = o.material; });
    if (!m) {
        process.stderr.write(`usd_materials: ${layer}: USDLoader built no probe mesh for '${name}'\n`);
        status = 2;
        continue;
    }
    console.log(JSON.stringify({
        name, type: m.type, color: m.color.toArray(), metalness: m.metalness, roughness: m.roughness, ior: m.ior,
        specularColor: m.specularColor.toArray(), specularIntensity: m.specularIntensity, clearcoat: m.clearcoat,
        clearcoatRoughness: m.clearcoatRoughness,
        maps: ['map', 'metalnessMap', 'roughnessMap', 'normalMap', 'specularColorMap'].filter((k) => m[k]),
    }));
}
process.exit(status);

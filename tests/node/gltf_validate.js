// gltf_validate.js — the Khronos glTF validator (npm gltf-validator, pinned in package-lock.json) over files.
//
// Usage: node gltf_validate.js [--all] FILE.gltf|FILE.glb ...
// External buffers and images are resolved relative to each file (URIs percent-decoded) and validated too.
// Prints one line per file: "FILE errors=N warnings=N infos=N hints=N", followed by one indented line per
// error (severity 0) with its code, JSON pointer and message (with --all, one per issue of any severity:
// error, warning, info, hint; e.g. to look for UNUSED_OBJECT infos). Exit status 1 if any file has an error or
// cannot be read, 0 otherwise.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const SEVERITY = ['error', 'warning', 'info', 'hint'];

async function validate(file, all) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const dir = path.dirname(file);
    const report = await validator.validateBytes(bytes, {
        uri: path.basename(file),
        maxIssues: 0,
        externalResourceFunction: (uri) =>
            new Promise((resolve, reject) => {
                fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, data) => {
                    if (err) reject(err.toString());
                    else resolve(new Uint8Array(data));
                });
            }),
    });
    const issues = report.issues;
    console.log(`${file} errors=${issues.numErrors} warnings=${issues.numWarnings} infos=${issues.numInfos} ` +
                `hints=${issues.numHints}`);
    for (const m of issues.messages) {
        if (m.severity === 0 || all)
            console.log(`    ${SEVERITY[m.severity] || m.severity} ${m.code} ${m.pointer || ''}: ${m.message}`);
    }
    return issues.numErrors;
}

(async () => {
    let bad = 0;
    const args = process.argv.slice(2);
    const all = args.includes('--all');
    for (const file of args.filter((a) => a !== '--all')) {
        try {
            if (await validate(file, all) > 0) bad++;
        } catch (e) {
            console.log(`${file} unreadable: ${e}`);
            bad++;
        }
    }
    process.exit(bad > 0 ? 1 : 0);
})();

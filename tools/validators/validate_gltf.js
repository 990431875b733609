#!/usr/bin/env node
// Validates .glb/.gltf files with the Khronos glTF-Validator. Prints the report's counts
// (errors, warnings, infos, hints) and every issue message; exits 1 when a file has an error or
// a warning, 2 when a file cannot be read.
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

const SEVERITY = ['error', 'warning', 'info', 'hint'];

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: (uri) =>
      Promise.resolve(new Uint8Array(fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri))))),
  });
  const issues = report.issues;
  console.log(`${file}: errors ${issues.numErrors}, warnings ${issues.numWarnings}, infos ${issues.numInfos}, hints ${issues.numHints}`);
  for (const message of issues.messages) console.log(`  [${SEVERITY[message.severity] || message.severity}] ${message.code} ${message.pointer || ''}: ${message.message}`);
  return issues.numErrors === 0 && issues.numWarnings === 0;
}

(async () => {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: validate_gltf.js FILE.glb...');
    process.exit(2);
  }
  let ok = true;
  for (const file of files) {
    try {
      ok = (await validate(file)) && ok;
    } catch (error) {
      console.error(`${file}: ${error.message || error}`);
      process.exit(2);
    }
  }
  process.exit(ok ? 0 : 1);
})();

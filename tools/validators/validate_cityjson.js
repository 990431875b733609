#!/usr/bin/env node
// Validates CityJSON files against the official CityJSON JSON Schemas with ajv.
// usage: validate_cityjson.js SCHEMA_FOLDER FILE.city.json...
// SCHEMA_FOLDER holds cityjson.schema.json and the schemas it refers to (all loaded, so no
// download happens). Exits 1 when a file is invalid, 2 when a file or schema cannot be read.
'use strict';
const fs = require('fs');
const path = require('path');
const Ajv = require('ajv');
const addFormats = require('ajv-formats');

function loadSchemas(folder) {
  const ajv = new Ajv({ allErrors: true, strict: false });
  addFormats(ajv);
  for (const name of fs.readdirSync(folder).filter((n) => n.endsWith('.schema.json')).sort())
    ajv.addSchema(JSON.parse(fs.readFileSync(path.join(folder, name), 'utf8')));
  const main = JSON.parse(fs.readFileSync(path.join(folder, 'cityjson.schema.json'), 'utf8'));
  return ajv.getSchema(main.$id);
}

const [folder, ...files] = process.argv.slice(2);
if (!folder || files.length === 0) {
  console.error('usage: validate_cityjson.js SCHEMA_FOLDER FILE.city.json...');
  process.exit(2);
}
let validate;
try {
  validate = loadSchemas(folder);
} catch (error) {
  console.error(`${folder}: ${error.message}`);
  process.exit(2);
}
let ok = true;
for (const file of files) {
  let document;
  try {
    document = JSON.parse(fs.readFileSync(file, 'utf8'));
  } catch (error) {
    console.error(`${file}: ${error.message}`);
    process.exit(2);
  }
  if (validate(document)) {
    console.log(`${file}: valid`);
  } else {
    ok = false;
    console.log(`${file}: ${validate.errors.length} schema errors`);
    for (const e of validate.errors.slice(0, 50)) console.log(`  ${e.instancePath || '/'} ${e.message} ${JSON.stringify(e.params)}`);
  }
}
process.exit(ok ? 0 : 1);

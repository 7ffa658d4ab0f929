// Validates glTF or GLB files with the Khronos glTF validator and prints its reports as one JSON
// array, in order. Usage: node validate-gltf.js FILE...
// Exit status 0 when the validator ran on every file (whatever it found), 2 when it could not
// (no file named, a file unreadable or of a format it cannot detect), 3 when the validator is not
// installed (run `npm ci` in tests/tools).
"use strict";
const fs = require("fs");

let validator;
try {
  validator = require("gltf-validator");
} catch (e) {
  console.error("missing: gltf-validator (npm ci in tests/tools)");
  process.exit(3);
}

async function main(files) {
  if (files.length === 0) {
    console.error("usage: node validate-gltf.js FILE...");
    process.exit(2);
  }
  const reports = [];
  for (const file of files) {
    let bytes;
    try {
      bytes = new Uint8Array(fs.readFileSync(file));
    } catch (e) {
      console.error(`cannot read ${file}: ${e.message}`);
      process.exit(2);
    }
    try {
      reports.push(
        await validator.validateBytes(bytes, { uri: file, maxIssues: 0, writeTimestamp: false })
      );
    } catch (e) {
      console.error(`the validator could not read ${file}: ${e}`);
      process.exit(2);
    }
  }
  console.log(JSON.stringify(reports));
}

main(process.argv.slice(2));

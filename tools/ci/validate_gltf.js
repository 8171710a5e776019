// Validates glTF files with the Khronos glTF-Validator (npm `gltf-validator`): prints each
// file's error / warning / info counts and its errors, and exits 1 when any file has an error
// (or cannot be read). Usage: node tools/ci/validate_gltf.js FILE.glb...
// NODE_PATH must reach a node_modules that holds gltf-validator (see .ci/run).
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

async function main(files) {
  let failed = 0;
  for (const file of files) {
    let report;
    try {
      report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
        uri: path.basename(file),
        maxIssues: 100,
      });
    } catch (e) {
      console.log(`${file}: cannot validate: ${e}`);
      failed += 1;
      continue;
    }
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages.filter((m) => m.severity === 0)) {
      console.log(`  error ${m.code}: ${m.message} at ${m.pointer || m.offset}`);
    }
    if (i.numErrors > 0) failed += 1;
  }
  if (failed > 0) {
    console.log(`${failed} file(s) failed validation`);
    process.exit(1);
  }
}

main(process.argv.slice(2)).catch((e) => {
  console.log(e);
  process.exit(1);
});

// node validate.mjs FILE...: the Khronos glTF validator's report of each file (images named by a URI
// read relative to it); exit 1 on any error.
import validator from 'gltf-validator';
import { readFileSync } from 'node:fs';
import { dirname, resolve } from 'node:path';

let failed = false;
for (const file of process.argv.slice(2)) {
  // images named by a URI are read relative to the file, so a dangling URI is an error
  const externalResourceFunction = async (uri) => new Uint8Array(readFileSync(resolve(dirname(file), decodeURIComponent(uri))));
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), { uri: file, externalResourceFunction });
  const { numErrors, numWarnings } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings`);
  for (const m of report.issues.messages)
    if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  failed ||= numErrors > 0;
}
process.exit(failed ? 1 : 0);

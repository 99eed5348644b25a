// Validate .glb / .gltf files with the Khronos glTF-Validator and print their JSON reports.
//
//   node validate_gltf.mjs path/to/file.glb               one report (a JSON object)
//   node validate_gltf.mjs a.glb b.gltf ...                one JSON array of reports, in order
//
// Exit code 0 when every report was produced (whatever they contain: the caller reads the
// counts), 2 when a file could not be read or the validator could not parse it at all.
import { readFile } from "node:fs/promises";
import path from "node:path";
import * as validator from "gltf-validator";

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node validate_gltf.mjs FILE.glb|FILE.gltf [...]");
  process.exit(2);
}

async function validate(file) {
  const fullPath = path.resolve(file);
  const bytes = new Uint8Array(await readFile(fullPath));
  return validator.validateBytes(bytes, {
    uri: path.basename(fullPath),
    maxIssues: 0, // unlimited: a test wants every issue, not the first few
    writeTimestamp: false,
    // Buffers and images referenced by URI live beside the file.
    externalResourceFunction: async (uri) =>
      new Uint8Array(await readFile(path.resolve(path.dirname(fullPath), decodeURIComponent(uri)))),
  });
}

const reports = [];
for (const file of files) {
  try {
    reports.push(await validate(file));
  } catch (error) {
    console.error(`validate_gltf: ${path.resolve(file)}: ${error}`);
    process.exit(2);
  }
}
process.stdout.write(JSON.stringify(files.length === 1 ? reports[0] : reports, null, 2) + "\n");

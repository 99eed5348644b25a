// Validate one .glb / .gltf file with the Khronos glTF-Validator and print its JSON report.
//
//   node validate_gltf.mjs path/to/file.glb
//
// Exit code 0 when a report was produced (whatever it contains: the caller reads the counts),
// 2 when the file could not be read or the validator could not parse it at all.
import { readFile } from "node:fs/promises";
import path from "node:path";
import * as validator from "gltf-validator";

const file = process.argv[2];
if (!file) {
  console.error("usage: node validate_gltf.mjs FILE.glb|FILE.gltf");
  process.exit(2);
}

const fullPath = path.resolve(file);
try {
  const bytes = new Uint8Array(await readFile(fullPath));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(fullPath),
    maxIssues: 0, // unlimited: a test wants every issue, not the first few
    writeTimestamp: false,
    // Buffers and images referenced by URI live beside the file.
    externalResourceFunction: async (uri) =>
      new Uint8Array(await readFile(path.resolve(path.dirname(fullPath), decodeURIComponent(uri)))),
  });
  process.stdout.write(JSON.stringify(report, null, 2) + "\n");
} catch (error) {
  console.error(`validate_gltf: ${fullPath}: ${error}`);
  process.exit(2);
}

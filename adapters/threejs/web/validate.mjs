// The Khronos glTF validator (npm gltf-validator, pinned) on one .gltf or .glb file: prints its report
// as JSON on stdout (the issues' counts and messages). Resources the file names are read beside it.
import { readFile } from "node:fs/promises";
import { dirname, join } from "node:path";
import validator from "gltf-validator";

const file = process.argv[2];
const data = await readFile(file);
const report = await validator.validateBytes(new Uint8Array(data), {
  uri: file,
  maxIssues: 100,
  externalResourceFunction: async (uri) => new Uint8Array(await readFile(join(dirname(file), decodeURIComponent(uri)))),
});
process.stdout.write(JSON.stringify({ validatorVersion: report.validatorVersion, issues: report.issues,
  extensionsUsed: report.info ? report.info.extensionsUsed : [] }));

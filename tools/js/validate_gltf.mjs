// Validates a .glb with the Khronos glTF validator; prints its summary and every error; exits 1 on
// errors. Usage: node tools/js/validate_gltf.mjs FILE.glb
import { readFileSync } from "node:fs";
import validator from "gltf-validator";

const path = process.argv[2];
if (!path) {
  console.error("usage: node validate_gltf.mjs FILE.glb");
  process.exit(2);
}
const report = await validator.validateBytes(new Uint8Array(readFileSync(path)), { maxIssues: 0 });
const { numErrors, numWarnings, numInfos, messages } = report.issues;
console.log(`${path}: ${numErrors} errors, ${numWarnings} warnings, ${numInfos} infos`);
const shown = new Map();
for (const m of messages) {
  if (m.severity > 1) continue;  // 0 error, 1 warning
  const key = `${m.severity === 0 ? "error" : "warning"} ${m.code}`;
  if (!shown.has(key)) shown.set(key, { count: 0, example: `${m.pointer ?? ""} ${m.message}` });
  shown.get(key).count += 1;
}
for (const [key, { count, example }] of shown) console.log(`  ${key} x${count}: ${example}`);
process.exit(numErrors > 0 ? 1 : 0);

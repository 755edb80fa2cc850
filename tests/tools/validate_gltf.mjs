#!/usr/bin/env node
// Validates a .gltf/.glb with the Khronos glTF validator (npm package gltf-validator).
//
// Usage: node tests/tools/validate_gltf.mjs <file.gltf>
// Prints the issue counts and each issue; exits 0 only when the report has no errors
// (warnings, infos and hints are printed but do not fail), 1 when it has errors and 2
// when the file cannot be read or validated at all.
// Setup: npm ci --prefix tests/tools   (installs the pinned version from package-lock.json)
import { createRequire } from 'node:module';
import { readFile } from 'node:fs/promises';
import path from 'node:path';

// createRequire resolves from this file's folder, so the package comes from
// tests/tools/node_modules whatever the caller's working directory is.
const require = createRequire(import.meta.url);

const SEVERITY = ['error', 'warning', 'info', 'hint'];

function usage() {
  console.error('usage: node tests/tools/validate_gltf.mjs <file.gltf|file.glb>');
  process.exit(2);
}

async function main() {
  const file = process.argv[2];
  if (!file || process.argv.length > 3) usage();

  let validator;
  try {
    validator = require('gltf-validator');
  } catch (e) {
    console.error(`validate_gltf: cannot load gltf-validator (${e.code ?? e.message}); ` +
                  'run: npm ci --prefix tests/tools');
    process.exit(2);
  }

  const bytes = new Uint8Array(await readFile(file));
  const dir = path.dirname(path.resolve(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,  // 0 = no limit: every issue is counted and listed
    // Only reached for external buffers or images; the project's scenes embed them.
    externalResourceFunction: (uri) =>
      readFile(path.resolve(dir, decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
  });

  const issues = report.issues;
  for (const m of issues.messages) {
    const where = m.pointer ?? (m.offset !== undefined ? `byte ${m.offset}` : '');
    console.log(`${SEVERITY[m.severity] ?? m.severity}: ${m.code} ${where}: ${m.message}`);
  }
  console.log(`${file}: errors=${issues.numErrors} warnings=${issues.numWarnings} ` +
              `infos=${issues.numInfos} hints=${issues.numHints}` +
              (issues.truncated ? ' (truncated)' : ''));
  process.exit(issues.numErrors === 0 ? 0 : 1);
}

main().catch((e) => {
  console.error(`validate_gltf: ${e?.message ?? e}`);
  process.exit(2);
});

#!/usr/bin/env node
// Runs the Khronos glTF validator (npm gltf-validator) on .glb/.gltf files and prints one JSON object per
// file: {file, errors, warnings, infos, hints, messages: [{code, severity, message, pointer}...]}.
// Exits 1 if any file has an error (or cannot be read), 0 otherwise.
// Usage: node scripts/validate-gltf.mjs FILE.glb [FILE2.glb ...]
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';
import path from 'node:path';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');
const SEVERITY = ['error', 'warning', 'info', 'hint'];

/** Validates one file's bytes; returns the summary object. */
export async function validateFile(file) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 100,
    externalResourceFunction: () => Promise.reject(new Error('external resources are not allowed')),
  });
  const issues = report.issues;
  return {
    file,
    validator: report.validatorVersion,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: issues.messages.map((m) => ({
      code: m.code,
      severity: SEVERITY[m.severity] ?? m.severity,
      message: m.message,
      pointer: m.pointer,
    })),
  };
}

if (import.meta.url === `file://${process.argv[1]}` || process.argv[1]?.endsWith('validate-gltf.mjs')) {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: node scripts/validate-gltf.mjs FILE.glb [FILE2.glb ...]');
    process.exit(2);
  }
  let failed = false;
  for (const f of files) {
    try {
      const r = await validateFile(f);
      console.log(JSON.stringify(r));
      if (r.errors > 0) failed = true;
    } catch (e) {
      console.log(JSON.stringify({ file: f, errors: 1, messages: [{ code: 'READ', severity: 'error', message: String(e) }] }));
      failed = true;
    }
  }
  process.exit(failed ? 1 : 0);
}

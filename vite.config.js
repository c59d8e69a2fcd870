// The page: index.html at the repository root, its code in www/, the wasm bindings in www/pkg/
// (scripts/build-wasm.sh). `base: './'` keeps every URL relative, so dist/ works from any static host or folder.
import { defineConfig } from 'vite';

const ignored = ['**/target/**', '**/node_modules/**', '**/dist/**', '**/pkg-node/**', '**/.git/**', '**/test-results/**'];

export default defineConfig({
  root: '.',
  base: './',
  publicDir: false,
  // Scan only the page for dependencies (not target/, which holds HTML of its own).
  optimizeDeps: { entries: ['index.html', 'explain.html'] },
  server: { host: '127.0.0.1', port: 5173, strictPort: false, watch: { ignored } },
  preview: { host: '127.0.0.1', port: 4173, strictPort: false },
  // www/main.js starts www/worker.js as a module worker ({ type: 'module' }): keep it an ES module when built.
  worker: { format: 'es' },
  // three.js alone is about 550 KB minified: one chunk is fine for a page loaded once from a local host.
  build: {
    outDir: 'dist', emptyOutDir: true, target: 'es2022', assetsInlineLimit: 0, chunkSizeWarningLimit: 1024,
    // The page, the article (explain.html), the embedding demo (www/embed-demo.html), the example paper page
    // (examples/paper-demo/, which embeds a model file), and www/mount.js as
    // dist/mount.js: a stable name with its exports kept, for other pages to import (mount(element, options)).
    rolldownOptions: {
      input: { index: 'index.html', explain: 'explain.html', 'embed-demo': 'www/embed-demo.html', 'paper-demo': 'examples/paper-demo/index.html', mount: 'www/mount.js' },
      preserveEntrySignatures: 'exports-only',
      output: { entryFileNames: (chunk) => (chunk.name === 'mount' ? 'mount.js' : 'assets/[name]-[hash].js') },
    },
  },
});

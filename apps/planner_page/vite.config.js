// The planner page: plain ES modules bundled by Vite into index.html and one script (no CDN, no network
// at run time), embedded in `pectus` (apps/serve/CMakeLists.txt).
import { defineConfig } from 'vite';

export default defineConfig({
  root: '.',
  base: '/',
  build: { assetsInlineLimit: 0, sourcemap: false, chunkSizeWarningLimit: 2000 },
});

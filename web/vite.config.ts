import { defineConfig } from "vite";

// `npm run dev` serves the console on :5173 and forwards the API and WebSockets to a running
// `tmeye serve --port 8080`; `npm run build` writes web/dist, which the server mounts at /.
const target = process.env.TMEYE_URL ?? "http://127.0.0.1:8080";

export default defineConfig({
  base: "./",
  build: { outDir: "dist", emptyOutDir: true, target: "es2022", sourcemap: true },
  server: {
    proxy: {
      "/api": { target, changeOrigin: false },
      "/ws": { target: target.replace(/^http/, "ws"), ws: true },
    },
  },
});

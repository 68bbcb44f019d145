// Saves a running server's OpenAPI document as web/openapi.json (then `npm run gen:api` types it):
//   TMEYE_URL=http://127.0.0.1:8080 npm run fetch:openapi
import { writeFileSync } from "node:fs";

const base = process.env.TMEYE_URL ?? "http://127.0.0.1:8080";
const res = await fetch(`${base}/api/openapi.json`);
if (!res.ok) throw new Error(`${base}/api/openapi.json: ${res.status}`);
writeFileSync(new URL("../openapi.json", import.meta.url), JSON.stringify(await res.json(), null, 4) + "\n");
console.log(`saved openapi.json from ${base}`);

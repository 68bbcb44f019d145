// Outlines of the enabled zone rules on the plan view (x right, z ahead, metres): a box's rectangle, a
// cylinder's circle (48 sides), each closed and followed by a gap.
import type { AlarmRuleOut } from "../api/types";
import type { XY } from "./plots";

export function zoneOutlines(rules: AlarmRuleOut[]): XY {
  const xs: (number | null)[] = [], zs: (number | null)[] = [];
  for (const r of rules) {
    const c = r.condition as Record<string, number | string>;
    if (c.kind !== "zone" || !r.enabled || r.out_of_service) continue;
    if (c.shape === "cylinder") {
      const cx = Number(c.center_x), cz = Number(c.center_z), rad = Number(c.radius);
      for (let k = 0; k <= 48; k++) {
        xs.push(cx + rad * Math.cos((2 * Math.PI * k) / 48));
        zs.push(cz + rad * Math.sin((2 * Math.PI * k) / 48));
      }
    } else {
      const x0 = Number(c.x_min), x1 = Number(c.x_max), z0 = Number(c.z_min), z1 = Number(c.z_max);
      xs.push(x0, x1, x1, x0, x0);
      zs.push(z0, z0, z1, z1, z0);
    }
    xs.push(null);
    zs.push(null);
  }
  return [xs, zs];
}

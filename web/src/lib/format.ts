export function num(v: number | null | undefined, digits = 2): string {
  return v === null || v === undefined || !Number.isFinite(v) ? "—" : v.toFixed(digits);
}

export function time(unixS: number | null | undefined): string {
  if (unixS === null || unixS === undefined) return "—";
  const d = new Date(unixS * 1000);
  return d.toLocaleString(undefined, { hour12: false });
}

export function clock(unixS: number): string {
  return new Date(unixS * 1000).toLocaleTimeString(undefined, { hour12: false });
}

export function duration(s: number): string {
  if (!Number.isFinite(s)) return "—";
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.round(s - m * 60)} s`;
}

/** Value for an <input type="datetime-local"> in local time. */
export function toLocalInput(unixS: number): string {
  const d = new Date(unixS * 1000);
  const p = (n: number) => String(n).padStart(2, "0");
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())}T${p(d.getHours())}:${p(d.getMinutes())}`;
}

export function fromLocalInput(v: string): number | undefined {
  if (!v) return undefined;
  const t = new Date(v).getTime();
  return Number.isFinite(t) ? t / 1000 : undefined;
}

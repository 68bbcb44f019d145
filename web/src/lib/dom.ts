// A tiny element builder: h("button", {class: "x", onclick: fn, "aria-label": "..."}, "text", child).
type Child = Node | string | number | null | undefined | false | Child[];
export type Attrs = Record<string, unknown>;

export function h<K extends keyof HTMLElementTagNameMap>(tag: K, attrs?: Attrs | null, ...children: Child[]):
  HTMLElementTagNameMap[K] {
  const el = document.createElement(tag);
  if (attrs) setAttrs(el, attrs);
  append(el, children);
  return el;
}

export function setAttrs(el: HTMLElement, attrs: Attrs): void {
  for (const [k, v] of Object.entries(attrs)) {
    if (v === undefined || v === null || v === false) continue;
    if (k.startsWith("on") && typeof v === "function") {
      el.addEventListener(k.slice(2), v as EventListener);
    } else if (k === "class") {
      el.className = String(v);
    } else if (k === "text") {
      el.textContent = String(v);
    } else if (k === "style" && typeof v === "object") {
      Object.assign(el.style, v);
    } else if (k === "dataset" && typeof v === "object") {
      Object.assign(el.dataset, v);
    } else if (k in el && !k.includes("-") && k !== "list" && k !== "form") {
      (el as unknown as Record<string, unknown>)[k] = v;
    } else {
      el.setAttribute(k, v === true ? "" : String(v));
    }
  }
}

export function append(el: Node, children: Child[]): void {
  for (const c of children) {
    if (c === null || c === undefined || c === false) continue;
    if (Array.isArray(c)) append(el, c);
    else el.appendChild(typeof c === "string" || typeof c === "number" ? document.createTextNode(String(c)) : c);
  }
}

export function clear(el: Element): void {
  while (el.firstChild) el.removeChild(el.firstChild);
}

let idSeq = 0;
export function uid(prefix = "id"): string {
  idSeq += 1;
  return `${prefix}-${idSeq}`;
}

/** A labelled form field: <div class="field"><label for>Label</label><input id></div>. */
export function field(label: string, input: HTMLElement, hint?: string): HTMLDivElement {
  if (!input.id) input.id = uid("f");
  const hintEl = hint ? h("small", { class: "hint", id: `${input.id}-hint` }, hint) : null;
  if (hintEl) input.setAttribute("aria-describedby", hintEl.id);
  return h("div", { class: "field" }, h("label", { for: input.id }, label), input, hintEl);
}

/** A message region (role=status or alert) whose text can be set. */
export function notice(kind: "status" | "alert" = "status"): HTMLParagraphElement & { show(msg: string, tone?: string): void } {
  const p = h("p", { class: "notice", role: kind, "aria-live": kind === "alert" ? "assertive" : "polite" }) as
    HTMLParagraphElement & { show(msg: string, tone?: string): void };
  p.show = (msg: string, tone = "info") => {
    p.textContent = msg;
    p.dataset.tone = tone;
    p.hidden = !msg;
  };
  p.hidden = true;
  return p;
}

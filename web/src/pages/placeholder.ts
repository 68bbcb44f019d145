import { h } from "../lib/dom";
import type { PageFactory } from "./types";

export function placeholder(title: string, text: string): PageFactory {
  return ({ root }) => {
    root.replaceChildren(h("section", { class: "page" }, h("h1", null, title), h("p", { class: "muted" }, text)));
    return {};
  };
}

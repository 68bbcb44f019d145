// The Settings page: the tracker's detection, identity and aiming settings as a form built from the
// OpenAPI document's schemas (limits, descriptions, defaults). Admins change them (PATCH of what changed,
// applied from the next frame); everyone else reads them.
import openapi from "../../openapi.json";
import { api, ApiError, errorText } from "../api/client";
import type { TrackerSettings } from "../api/types";
import { h, notice, uid } from "../lib/dom";
import { atLeast, roleReason, type Session } from "../lib/session";
import type { Page, PageContext } from "./types";

interface Prop {
  type?: string;
  title?: string;
  description?: string;
  minimum?: number;
  maximum?: number;
  exclusiveMinimum?: number;
  default?: number;
}

type Section = keyof TrackerSettings;
const SECTIONS: { key: Section; schema: string; title: string }[] = [
  { key: "detector", schema: "DetectorSettings", title: "Detection" },
  { key: "tracks", schema: "TracksSettings", title: "Identity (tracks)" },
  { key: "aim", schema: "AimSettings", title: "Aiming" },
];

const schemas = (openapi as unknown as { components: { schemas: Record<string, { properties: Record<string, Prop> }> } })
  .components.schemas;

/** One setting's labelled number input, with its limits, description and default as a hint. */
function settingField(key: Section, name: string, prop: Prop, canEdit: boolean): { row: HTMLElement; input: HTMLInputElement } {
  const id = uid("set");
  const input = h("input", { id, name: `${key}.${name}`, type: "number", required: true,
    step: prop.type === "integer" ? 1 : "any",
    min: prop.minimum ?? prop.exclusiveMinimum, max: prop.maximum, readOnly: !canEdit,
    "aria-describedby": `${id}-hint` });
  const limits = [prop.minimum !== undefined ? `≥ ${prop.minimum}` : prop.exclusiveMinimum !== undefined
    ? `> ${prop.exclusiveMinimum}` : "", prop.maximum !== undefined ? `≤ ${prop.maximum}` : ""].filter(Boolean).join(", ");
  const row = h("div", { class: "field setting" },
    h("label", { for: id }, prop.title ?? name, h("code", { class: "muted small" }, ` ${name}`)), input,
    h("small", { class: "hint", id: `${id}-hint` },
      [prop.description, limits, prop.default !== undefined ? `default ${prop.default}` : ""].filter(Boolean).join("; ")));
  return { row, input };
}

/** The settings whose inputs differ from `current` (empty inputs left out), by section: a PATCH body. */
function changes(inputs: Iterable<{ section: Section; name: string; input: HTMLInputElement }>, current: TrackerSettings
): Record<string, Record<string, number>> {
  const patch: Record<string, Record<string, number>> = {};
  for (const { section, name, input } of inputs) {
    const old = (current[section] as Record<string, unknown>)[name];
    if (input.value === "" || String(old) === input.value) continue;
    (patch[section] ??= {})[name] = Number(input.value);
  }
  return patch;
}

/** A setting's input with its place (section, name) and schema. */
interface SettingInput {
  section: Section;
  name: string;
  input: HTMLInputElement;
  prop: Prop;
}

/** A fieldset per section with its settings' fields; each input put in inputs under "section.name". */
function settingFieldsets(canEdit: boolean, inputs: Map<string, SettingInput>): HTMLFieldSetElement[] {
  return SECTIONS.map(({ key, schema, title }) => {
    const props = schemas[schema]?.properties ?? {};
    const rows = Object.entries(props).map(([name, prop]) => {
      const { row, input } = settingField(key, name, prop, canEdit);
      inputs.set(`${key}.${name}`, { section: key, name, input, prop });
      return row;
    });
    return h("fieldset", { class: "panel settings-group" }, h("legend", null, title), ...rows);
  });
}

/** Show the settings in their inputs, none marked as changed. */
function fillInputs(inputs: Iterable<SettingInput>, current: TrackerSettings): void {
  for (const { section, name, input } of inputs) {
    const v = (current[section] as Record<string, unknown>)[name];
    input.value = v === undefined || v === null ? "" : String(v);
    input.classList.remove("changed");
  }
}

/** Mark an input as changed while its value differs from the current setting (current(): null until loaded). */
function markChanges(inputs: Iterable<SettingInput>, current: () => TrackerSettings | null): void {
  for (const { section, name, input } of inputs) {
    input.addEventListener("input", () => {
      const cur = current();
      const v = cur ? (cur[section] as Record<string, unknown>)[name] : undefined;
      input.classList.toggle("changed", String(v) !== input.value);
    });
  }
}

/** PATCH the changed settings and say how many were saved, or why not; saved: with the settings now in force. */
async function saveChanges(patch: Record<string, Record<string, number>>, msg: ReturnType<typeof notice>,
  saved: (s: TrackerSettings) => void): Promise<void> {
  try {
    saved(await api.patchTrackerConfig(patch));
    const n = Object.values(patch).reduce((a, s) => a + Object.keys(s).length, 0);
    msg.show(`Saved ${n} setting${n === 1 ? "" : "s"}: applied from the next frame.`, "ok");
  } catch (e) {
    msg.show(e instanceof ApiError && e.status === 403 ? `Refused: ${e.detail}` :
      `Not saved: ${errorText(e)}`, "bad");
  }
}

/** The line above the form: when changes apply (admin), or why this session may only read them. */
function settingsIntro(session: Session, canEdit: boolean): HTMLParagraphElement {
  return canEdit ? h("p", { class: "muted" }, "Changes apply from the next frame and are kept across restarts.")
    : h("p", { class: "reason", id: "settings-reason", role: "note", "data-testid": "settings-reason" },
      `${roleReason(session, "admin", "Changing the tracker settings")} You can read them.`);
}

export function settingsPage(ctx: PageContext): Page {
  const { root, session } = ctx;
  const canEdit = atLeast(session, "admin");
  const msg = notice("status");
  const inputs = new Map<string, SettingInput>();
  let current: TrackerSettings | null = null;
  const fill = () => {
    if (current) fillInputs(inputs.values(), current);
  };

  const fieldsets = settingFieldsets(canEdit, inputs);
  const save = h("button", { type: "submit", class: "primary", disabled: !canEdit }, "Save changes");
  const reset = h("button", { type: "button", disabled: !canEdit, onclick: () => fill() }, "Undo edits");
  const form = h("form", { class: "settings-form", "aria-describedby": canEdit ? undefined : "settings-reason" },
    ...fieldsets, h("div", { class: "actions" }, save, reset));
  root.replaceChildren(h("section", { class: "page" }, h("h1", null, "Tracker settings"),
    settingsIntro(session, canEdit), msg, form));

  markChanges(inputs.values(), () => current);

  async function load(): Promise<void> {
    try {
      current = await api.trackerConfig();
      fill();
      msg.show("", "info");
    } catch (e) {
      msg.show(`Settings could not be loaded: ${errorText(e)}`, "bad");
    }
  }

  // the browser checks each field's limits before submitting: say which one is out of range
  form.addEventListener("invalid", (ev) => {
    const input = ev.target as HTMLInputElement;
    const item = inputs.get(input.name);
    msg.show(`Not saved: ${item?.prop.title ?? input.name}: ${input.validationMessage}`, "bad");
  }, true);
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    if (!canEdit || !current) return;
    const patch = changes(inputs.values(), current);
    if (!Object.keys(patch).length) {
      msg.show("Nothing changed.", "info");
      return;
    }
    save.disabled = true;
    try {
      await saveChanges(patch, msg, (s) => {
        current = s;
        fill();
      });
    } finally {
      save.disabled = false;
    }
  });

  void load();
  return {};
}

// Alarm rules for admins (part of the Alarms page): the list with enabled / out-of-service switches and
// delete (the built-in device fault rules: out of service only), each rule's alarm state, and a form for a new rule whose fields follow the chosen condition (metres, m/s, seconds).
import { api, errorText } from "../api/client";
import type { AlarmRuleIn, AlarmRuleOut, Priority } from "../api/types";
import { PRIORITIES, stateText } from "../lib/alarms";
import { field, h } from "../lib/dom";

type Notice = HTMLParagraphElement & { show(msg: string, tone?: string): void };
/** A change of a rule's switches (PATCH body). */
type RulePatch = { enabled?: boolean; out_of_service?: boolean };

/** Per condition kind: its fields (name, label, required). */
const KINDS: Record<string, [string, string, boolean][]> = {
  "zone box": [["x_min", "x min (m)", true], ["x_max", "x max (m)", true], ["z_min", "z min (m, ahead)", true],
    ["z_max", "z max (m)", true], ["y_min", "y min (m, down)", false], ["y_max", "y max (m)", false],
    ["dwell_s", "dwell (s)", false]],
  "zone cylinder": [["center_x", "centre x (m)", true], ["center_z", "centre z (m)", true],
    ["radius", "radius (m)", true], ["y_min", "y min (m, down)", false], ["y_max", "y max (m)", false],
    ["dwell_s", "dwell (s)", false]],
  range_below: [["distance_m", "closer than (m)", true]],
  approach: [["speed_mps", "closing faster than (m/s)", true], ["for_s", "for at least (s)", false],
    ["deadband_mps", "deadband (m/s, default 0.3)", false]],
  size: [["width_min", "width min (m)", false], ["width_max", "width max (m)", false],
    ["height_min", "height min (m)", false], ["height_max", "height max (m)", false]],
  lost: [["after_s", "lost for longer than (s)", true]],
};

export function describeCondition(c: Record<string, unknown>): string {
  return Object.entries(c).filter(([k]) => k !== "kind").map(([k, v]) => `${k} ${v}`).join(", ");
}

/** A rule's row: its cells, the enabled switch (not built in) and the out-of-service switch (patch: a change of
 * one), delete (remove; built-in rules: none). */
function ruleRow(r: AlarmRuleOut, patch: (r: AlarmRuleOut, body: RulePatch) => void, remove: (r: AlarmRuleOut) => void
): HTMLTableRowElement {
  const en = h("input", { type: "checkbox", checked: r.enabled, disabled: r.built_in, "aria-label": `${r.name} enabled` });
  const oos = h("input", { type: "checkbox", checked: r.out_of_service, "aria-label": `${r.name} out of service` });
  en.addEventListener("change", () => patch(r, { enabled: en.checked }));
  oos.addEventListener("change", () => patch(r, { out_of_service: oos.checked }));
  const del = r.built_in ? h("span", { class: "muted" }, "built in")
    : h("button", { type: "button", onclick: () => remove(r) }, "Delete");
  return h("tr", { "data-rule": String(r.id), "data-built-in": String(r.built_in) }, h("td", null, r.name),
    h("td", { class: `prio-${r.priority}` }, r.priority),
    h("td", null, `${r.condition.kind}: ${describeCondition(r.condition)}`),
    h("td", null, `${r.on_delay_s} s / ${r.off_delay_s} s`), h("td", null, stateText(r.state)),
    h("td", null, en), h("td", null, oos), h("td", null, del));
}

/** The form for a new rule: name, priority, the condition with its fields (following the chosen kind), delays.
 * create: on submit, with the rule's body and a reset of the form (after it was created). */
function ruleForm(create: (body: AlarmRuleIn, reset: () => void) => void): HTMLFormElement {
  const name = h("input", { name: "rule-name", required: true, maxLength: 128 });
  const prio = h("select", { name: "rule-priority" }, ...PRIORITIES.map((p) => h("option", { value: p }, p)));
  const kind = h("select", { name: "rule-kind" }, ...Object.keys(KINDS).map((k) => h("option", { value: k }, k)));
  const onDelay = h("input", { type: "number", name: "rule-on-delay", min: 0, max: 3600, step: "any", value: 0 });
  const offDelay = h("input", { type: "number", name: "rule-off-delay", min: 0, max: 3600, step: "any", value: 2 });
  const fields = h("div", { class: "row-form" });
  const inputs = new Map<string, HTMLInputElement>();
  const form = h("form", { class: "row-form", "aria-label": "New alarm rule" }, field("Name", name), field("Priority", prio),
    field("Condition", kind), fields, field("On-delay (s)", onDelay), field("Off-delay (s)", offDelay),
    h("button", { type: "submit", class: "primary" }, "Create rule"));

  function showFields(): void {
    inputs.clear();
    fields.replaceChildren(...KINDS[kind.value].map(([key, label, req]) => {
      const el = h("input", { type: "number", step: "any", name: `rule-${key}`, required: req });
      inputs.set(key, el);
      return field(label, el, req ? undefined : "optional");
    }));
  }
  kind.addEventListener("change", showFields);
  showFields();

  form.addEventListener("submit", (ev) => {
    ev.preventDefault();
    const [k, shape] = kind.value.split(" ");
    const condition: Record<string, unknown> = { kind: k };
    if (shape) condition.shape = shape;
    for (const [key, el] of inputs) if (el.value !== "") condition[key] = Number(el.value);
    const body = { name: name.value.trim(), priority: prio.value as Priority, condition,
      on_delay_s: Number(onDelay.value), off_delay_s: Number(offDelay.value) } as unknown as AlarmRuleIn;
    create(body, () => {
      form.reset();
      showFields();
    });
  });
  return form;
}

export function rulesPanel(msg: Notice): HTMLElement {
  const tbody = h("tbody");
  const table = h("table", { class: "data", "data-testid": "rule-table" }, h("caption", { class: "sr-only" }, "Alarm rules"),
    h("thead", null, h("tr", null, ...["Rule", "Priority", "Condition", "On / off delay", "State", "Enabled", "Out of service", ""]
      .map((c) => h("th", { scope: "col" }, c)))), tbody);
  const fail = (what: string, e: unknown) => msg.show(`${what}: ${errorText(e)}`, "bad");
  const form = ruleForm((body, reset) => void api.createAlarmRule(body).then(() => {
    msg.show(`Rule ${body.name} created.`, "ok");
    reset();
    return load();
  }, (e) => fail("The rule was not created", e)));

  async function load(): Promise<void> {
    let rules: AlarmRuleOut[];
    try {
      rules = await api.alarmRules();
    } catch (e) {
      fail("Rules could not be loaded", e);
      return;
    }
    tbody.replaceChildren(...rules.map((r) => ruleRow(r, (x, body) => void patch(x, body), (x) => void remove(x))));
  }

  async function patch(r: AlarmRuleOut, body: RulePatch): Promise<void> {
    try {
      await api.patchAlarmRule(r.id, body);
      msg.show(`Rule ${r.name} changed.`, "ok");
    } catch (e) {
      fail(`Rule ${r.name}`, e);
    }
    await load();
  }

  async function remove(r: AlarmRuleOut): Promise<void> {
    if (!confirm(`Delete the rule ${r.name}? Its open alarm ends.`)) return;
    try {
      await api.deleteAlarmRule(r.id);
      msg.show(`Rule ${r.name} deleted.`, "ok");
    } catch (e) {
      fail(`Rule ${r.name}`, e);
    }
    await load();
  }

  void load();
  return h("section", { class: "panel", "aria-labelledby": "rules-title" }, h("h2", { id: "rules-title" }, "Rules"),
    h("div", { class: "table-wrap" }, table), h("h3", null, "New rule"), form);
}

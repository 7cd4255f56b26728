// The routine being recorded lives beside the page, not in it: the user goes to Manual motion to move the arm and
// comes back to add the next pose, and the draft is still there (for this tab; nothing is sent until "Save as").

/** @type {{ steps: import('./logic.js').Step[], group: string, tool: string, action: string, name: string }} */
export const draft = $state({ steps: [], group: '', tool: '', action: '', name: '' });

/** After a save, or on logout. */
export function clearDraft() {
  draft.steps = [];
  draft.name = '';
}

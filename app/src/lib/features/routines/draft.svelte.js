// The routine being recorded lives beside the page, not in it: the user goes to Manual motion to move the arm and
// comes back to add the next pose, and the draft is still there (for this tab; nothing is sent until "Save as").
// It belongs to the user who recorded it: another user signing in on the same phone starts from an empty draft.

/** @type {{ steps: import('./logic.js').Step[], group: string, tool: string, action: string, name: string, owner: string }} */
export const draft = $state({ steps: [], group: '', tool: '', action: '', name: '', owner: '' });

/** After a save. */
export function clearDraft() {
  draft.steps = [];
  draft.name = '';
}

/**
 * The draft for this user: kept if they recorded it, else emptied (steps, name and choices) and theirs from now on.
 * @param {string} username
 */
export function draftFor(username) {
  if (draft.owner === username) return;
  Object.assign(draft, { steps: [], group: '', tool: '', action: '', name: '', owner: username });
}

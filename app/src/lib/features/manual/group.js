// The motion group chosen on the Manual page, remembered for the browser tab's session (sessionStorage: it
// survives a reload and going to another page and back, not closing the tab). Display choice only: nothing is sent.

export const GROUP_KEY = 'cell-ui.manual.group';

/** @returns {Storage | null} */
function store() {
  try {
    return typeof sessionStorage === 'undefined' ? null : sessionStorage;
  } catch {
    return null; // storage disabled (privacy settings)
  }
}

/** The remembered group, '' when none. @returns {string} */
export function rememberedGroup() {
  try {
    return store()?.getItem(GROUP_KEY) ?? '';
  } catch {
    return '';
  }
}

/** @param {string} group */
export function rememberGroup(group) {
  try {
    if (group) store()?.setItem(GROUP_KEY, group);
    else store()?.removeItem(GROUP_KEY);
  } catch {
    /* full or disabled: the choice lasts while the page is open */
  }
}

// What a role may see of the cell file: pure functions of (cell, role).

/** @param {import('../config/cell-types.js').Cell} cell @param {string} role @returns {{id: string, title: string}[]} */
export function pagesFor(cell, role) {
  const allowed = new Set(cell.roles[role]?.pages || []);
  return cell.pages.filter((p) => allowed.has(p.id)).map(({ id, title }) => ({ id, title }));
}

/** @param {import('../config/cell-types.js').Cell} cell @param {string} role @param {string} pageId */
export function mayViewPage(cell, role, pageId) {
  return (cell.roles[role]?.pages || []).includes(pageId);
}

/**
 * The cell file as the UI of this role needs it. Feature sections are added here as their pages land,
 * each only for roles that see the page.
 * @param {import('../config/cell-types.js').Cell} cell @param {string} role
 */
export function configFor(cell, role) {
  const { topic, type, modes } = cell.operation_mode;
  return {
    cell: { id: cell.cell.id, name: cell.cell.name, description: cell.cell.description || '' },
    role,
    pages: pagesFor(cell, role),
    operation_mode: { topic, type, modes },
  };
}

// JSDoc types of the cell file's core (config/cell.schema.json is the authority; feature sections: config/features/).
/**
 * @typedef {{subscribe?: string[], publish?: string[], call_service?: string[], advertise?: string[], advertise_service?: string[]}} RosGrants
 * @typedef {{title?: string, pages: string[], commands?: string[], take_over?: boolean, ros?: RosGrants}} Role
 * @typedef {{id: string, title: string}} Page
 * @typedef {{topic: string, type: string, get_service?: string, set_service?: string, modes: string[], initial?: string}} OperationMode
 * @typedef {{cell: {id: string, name: string, description?: string}, pages: Page[], roles: Record<string, Role>,
 *   operation_mode: OperationMode, [section: string]: any}} Cell
 */
export {};

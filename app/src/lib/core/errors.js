/**
 * The BFF's client errors in the user's language: the body's stable `code` and `params` pick a message of the
 * catalogue (messages/errors); an unknown code (a newer BFF, a feature's own error) shows the BFF's English text.
 */
import { m } from '$lib/paraglide/messages.js';

/** @type {Record<string, (p: Record<string, any>) => string>} */
const BY_CODE = {
  'auth.invalid_credentials': () => m.errors_auth_invalid_credentials(),
  'auth.throttled': (p) => m.errors_auth_throttled({ seconds: String(p.seconds ?? '?') }),
  'auth.not_logged_in': () => m.errors_auth_not_logged_in(),
  'auth.no_account': () => m.errors_auth_no_account(),
  'access.page_denied': (p) => m.errors_access_page_denied({ role: String(p.role ?? '') }),
  'control.not_mover': (p) => m.errors_control_not_mover({ role: String(p.role ?? '') }),
  'control.held': (p) => m.errors_control_held({ user: String(p.user ?? ''), role: String(p.role ?? '') }),
  'control.not_holder': () => m.errors_control_not_holder(),
  'request.invalid': (p) => m.errors_request_invalid({ detail: String(p.detail ?? '') }),
  'request.malformed_json': () => m.errors_request_malformed_json(),
  'request.not_json': () => m.errors_request_not_json(),
  'request.too_large': (p) => m.errors_request_too_large({ limit: String(p.limit ?? '?') }),
  'request.cross_origin': () => m.errors_request_cross_origin(),
  'upload.too_large': () => m.errors_upload_too_large(),
  'database.invalid_path': () => m.errors_database_invalid_path(),
  'database.not_a_directory': () => m.errors_database_not_a_directory(),
  'database.not_a_file': () => m.errors_database_not_a_file(),
  'database.too_large': (p) => m.errors_database_too_large({ limit: str(p.limit, '?') }),
  'database.invalid_backup': (p) => m.errors_database_invalid_backup({ file: str(p.file) }),
  'database.no_backup': (p) => m.errors_database_no_backup({ backup: str(p.backup) }),
  'database.invalid_name': () => m.errors_database_invalid_name(),
  'database.not_listed': (p) => m.errors_database_not_listed({ file: str(p.file) }),
  // expected, got: '' for a name without an extension.
  'database.bad_extension': (p) => {
    const file = str(p.file);
    const expected = str(p.expected);
    const got = str(p.got);
    if (!expected) return m.errors_database_bad_extension_want_none({ file, got });
    if (!got) return m.errors_database_bad_extension_none({ file, expected });
    return m.errors_database_bad_extension({ file, expected, got });
  },
  'database.invalid_drive': () => m.errors_database_invalid_drive(),
  'database.no_drive': (p) => m.errors_database_no_drive({ drive: str(p.drive) }),
  'database.no_such_path': (p) => m.errors_database_no_such_path({ path: str(p.path) }),
  'database.not_readable': (p) => m.errors_database_not_readable({ path: str(p.path) }),
  'database.outside_drive': () => m.errors_database_outside_drive(),
  'database.not_multipart': () => m.errors_database_not_multipart(),
  'database.no_file': () => m.errors_database_no_file(),
  'database.one_file': () => m.errors_database_one_file(),
  'database.empty_file': (p) => m.errors_database_empty_file({ file: str(p.file) }),
  'database.nul_bytes': (p) => m.errors_database_nul_bytes({ file: str(p.file) }),
  'database.not_utf8': (p) => m.errors_database_not_utf8({ file: str(p.file) }),
  'database.bad_json': (p) => m.errors_database_bad_json({ file: str(p.file), detail: str(p.detail) }),
  'database.bad_yaml': (p) => (p.line === undefined || p.line === null
    ? m.errors_database_bad_yaml_no_line({ file: str(p.file), detail: str(p.detail) })
    : m.errors_database_bad_yaml({ file: str(p.file), detail: str(p.detail), line: str(p.line) })),
  'database.csv_columns': (p) => m.errors_database_csv_columns({ file: str(p.file), line: str(p.line, '?'), columns: str(p.columns, '?'), expected: str(p.expected, '?') }),
  'database.csv_stray_quote': (p) => m.errors_database_csv_stray_quote({ file: str(p.file), line: str(p.line, '?') }),
  'database.csv_unclosed_quote': (p) => m.errors_database_csv_unclosed_quote({ file: str(p.file), line: str(p.line, '?') }),
  'database.csv_text_after_quote': (p) => m.errors_database_csv_text_after_quote({ file: str(p.file), line: str(p.line, '?') }),
  'database.csv_no_rows': (p) => m.errors_database_csv_no_rows({ file: str(p.file) }),
  'scene.master_down': (p) => m.errors_scene_master_down({ master: str(p.master) }),
  'scene.master_bad_uri': (p) => m.errors_scene_master_bad_uri({ master: str(p.master) }),
  'scene.master_not_xmlrpc': (p) => m.errors_scene_master_not_xmlrpc({ master: str(p.master), detail: str(p.detail) }),
  'scene.master_refused': (p) => m.errors_scene_master_refused({ master: str(p.master), param: str(p.param), detail: str(p.detail) }),
  'scene.master_bad_answer': (p) => m.errors_scene_master_bad_answer({ master: str(p.master) }),
  'scene.master_answer_too_large': (p) => m.errors_scene_master_answer_too_large({ limit: str(p.limit, '?') }),
  'scene.param_unset': (p) => m.errors_scene_param_unset({ param: str(p.param) }),
  'scene.param_not_string': (p) => m.errors_scene_param_not_string({ param: str(p.param) }),
  'scene.param_not_urdf': (p) => m.errors_scene_param_not_urdf({ param: str(p.param), detail: str(p.detail) }),
  'scene.param_root_not_robot': (p) => m.errors_scene_param_root_not_robot({ param: str(p.param), root: str(p.root) }),
  'scene.file_not_urdf': (p) => m.errors_scene_file_not_urdf({ file: str(p.file), detail: str(p.detail) }),
  'scene.file_root_not_robot': (p) => m.errors_scene_file_root_not_robot({ file: str(p.file), root: str(p.root) }),
  'scene.file_too_large': (p) => m.errors_scene_file_too_large({ file: str(p.file), limit: str(p.limit, '?') }),
  'scene.file_unreadable': (p) => m.errors_scene_file_unreadable({ file: str(p.file), field: str(p.field), reason: str(p.reason) }),
  'scene.no_arm': (p) => m.errors_scene_no_arm({ arm: str(p.arm) }),
  'scene.arm_no_urdf': (p) => m.errors_scene_arm_no_urdf({ arm: str(p.arm) }),
  'scene.no_mesh': (p) => m.errors_scene_no_mesh({ arm: str(p.arm), index: str(p.index), name: str(p.name) }),
  'scene.mesh_format': (p) => m.errors_scene_mesh_format({ name: str(p.name) }),
  'scene.mesh_not_local': (p) => m.errors_scene_mesh_not_local({ name: str(p.name) }),
  'scene.mesh_no_package': (p) => m.errors_scene_mesh_no_package({ name: str(p.name), package: str(p.package) }),
  'scene.mesh_scheme': (p) => m.errors_scene_mesh_scheme({ name: str(p.name), scheme: str(p.scheme) }),
  'scene.mesh_private': (p) => m.errors_scene_mesh_private({ name: str(p.name) }),
  'scene.mesh_unreadable': (p) => m.errors_scene_mesh_unreadable({ name: str(p.name), reason: str(p.reason) }),
  'recorder.invalid_name': (p) => m.errors_recorder_invalid_name({ name: str(p.name) }),
  'recorder.not_found': (p) => m.errors_recorder_not_found({ name: str(p.name) }),
  'recorder.delete_denied': (p) => m.errors_recorder_delete_denied({ role: str(p.role) }),
};

/** A parameter as text ('' or the fallback when absent). @param {unknown} v @param {string} [fallback] */
function str(v, fallback = '') {
  return v === undefined || v === null ? fallback : String(v);
}

/**
 * @param {any} body  the JSON body of an error answer
 * @returns {string} the text for the user ('' when the body says nothing)
 */
export function errorText(body) {
  if (!body || typeof body !== 'object') return '';
  const say = typeof body.code === 'string' && Object.hasOwn(BY_CODE, body.code) ? BY_CODE[body.code] : null;
  if (say) return say(body.params && typeof body.params === 'object' ? body.params : {});
  return typeof body.error === 'string' ? body.error : '';
}

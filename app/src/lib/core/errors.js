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
};

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

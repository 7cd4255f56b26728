// Client errors raised below our handlers (the URL decoder, the body parsers, multipart parsing) mapped to a
// 4xx status and a clear message. Anything else is a bug or a server-side failure: 500, logged.

/**
 * @typedef {{status: number, message: string, code?: string, params?: Record<string, string | number>}} HttpError
 */

/**
 * A client error's JSON body: the English sentence (for logs, curl and older apps) and a stable code with its
 * parameters, which the app turns into a text in the user's language (app/messages/errors).
 * @param {string} message @param {string} code @param {Record<string, string | number>} [params]
 */
export function errorBody(message, code, params) {
  return params ? { error: message, code, params } : { error: message, code };
}

/** Multer's own error codes (multer.MulterError), with the status and message the client gets. */
const MULTER = {
  LIMIT_FILE_SIZE: [413, 'the file is larger than the upload limit', 'upload.too_large'],
  LIMIT_FIELD_VALUE: [413, 'a form field value is too long'],
  LIMIT_FIELD_KEY: [400, 'a form field name is too long'],
  LIMIT_PART_COUNT: [400, 'too many parts in the multipart body'],
  LIMIT_FIELD_COUNT: [400, 'too many form fields in the multipart body'],
  LIMIT_FILE_COUNT: [400, 'only one file may be sent'],
  LIMIT_UNEXPECTED_FILE: [400, 'unexpected file field'],
  MISSING_FIELD_NAME: [400, 'a part of the multipart body has no field name'],
};

/** body-parser's error types (express.json and friends). */
const BODY = {
  'entity.parse.failed': (e) => [400, 'malformed JSON body', 'request.malformed_json'],
  'entity.too.large': (e) => [413, `request body larger than the limit of ${e.limit} bytes`, 'request.too_large', { limit: e.limit }],
  'encoding.unsupported': (e) => [415, `unsupported content encoding "${e.encoding}"`],
  'charset.unsupported': (e) => [415, `unsupported charset "${e.charset}"`],
  'request.aborted': () => [400, 'request aborted'],
  'request.size.invalid': () => [400, 'request body size does not match Content-Length'],
  'entity.verify.failed': () => [403, 'request body refused'],
};

/**
 * The client's share of an error: status 400-499 with a message meant for the user, or 500 'internal error'.
 * @param {any} err
 * @returns {HttpError & {clientError: boolean}}
 */
export function httpError(err) {
  const out = (status, message, code = undefined, params = undefined) => ({ status, message, clientError: status < 500, ...(code ? { code } : {}), ...(params ? { params } : {}) });
  if (!err || typeof err !== 'object') return out(500, 'internal error');
  // Express 5 decodes path parameters with decodeURIComponent and marks a failure 400 ("Failed to decode param").
  if (err instanceof URIError) return out(400, 'malformed percent-encoding in the URL');
  if (err.name === 'MulterError') return multerError(err);
  if (typeof err.type === 'string' && BODY[err.type]) return out(...BODY[err.type](err));
  const status = Number(err.status ?? err.statusCode);
  if (Number.isInteger(status) && status >= 400 && status < 500 && err.expose !== false) {
    return out(status, String(err.message || 'bad request'), typeof err.code === 'string' && /^[a-z_]+\.[a-z_.]+$/.test(err.code) ? err.code : undefined, err.params);
  }
  return out(500, 'internal error');
}

/** @param {{code?: string, field?: string, message?: string}} err */
export function multerError(err) {
  const [status, message, code] = MULTER[err.code] || [400, `bad upload: ${err.message}`];
  const field = err.field ? ` ("${String(err.field).slice(0, 64)}")` : '';
  return { status, message: `${message}${field}`, clientError: true, ...(code ? { code } : {}) };
}

/**
 * What came out of parsing a multipart body: multer's limits, busboy's parse errors (a malformed body: no boundary,
 * bad part headers, unexpected end) are the client's; file-system errors while spooling (they name a syscall) are ours.
 * @param {any} err
 * @returns {HttpError & {clientError: boolean}}
 */
export function multipartError(err) {
  if (err?.name === 'MulterError') return multerError(err);
  if (err && typeof err === 'object' && !err.syscall && !(err instanceof TypeError) && !(err instanceof RangeError)) {
    return { status: 400, message: `malformed multipart body: ${String(err.message || err).slice(0, 200)}`, clientError: true };
  }
  return httpError(err);
}

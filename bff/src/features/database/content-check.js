// Content sanity checks by file type, before a database file is replaced. Pure functions of the bytes.
import yaml from 'js-yaml';

/**
 * Thrown when the content does not parse; `message` is shown to the user. `code` and `params`: the same for the app
 * to say in the user's language (`database.csv_columns` {line, columns, expected}); the file's name is added by the caller.
 */
export class ContentError extends Error {
  /** @param {string} message @param {string} [code] @param {Record<string, string | number>} [params] */
  constructor(message, code = undefined, params = undefined) {
    super(message);
    this.code = code;
    this.params = params;
  }
}

/**
 * Checks .csv, .json, .yaml/.yml content; other extensions are not checked.
 * @param {string} ext lower-case extension with the dot (".csv")
 * @param {Buffer} buf
 * @throws {ContentError}
 */
export function checkContent(ext, buf) {
  if (!['.csv', '.json', '.yaml', '.yml'].includes(ext)) return;
  if (buf.length === 0) throw new ContentError('the file is empty', 'database.empty_file');
  if (buf.includes(0)) throw new ContentError('the file contains NUL bytes (binary, or UTF-16 text; save it as UTF-8)', 'database.nul_bytes');
  if (ext === '.csv') {
    // Delimiters and quotes are ASCII, so the byte structure is the same in UTF-8 and in 8-bit code pages.
    checkCsv(buf.toString('latin1').replace(/^\xEF\xBB\xBF/, ''));
    return;
  }
  let text;
  try {
    text = new TextDecoder('utf-8', { fatal: true }).decode(buf).replace(/^\uFEFF/, '');
  } catch {
    throw new ContentError('the file is not UTF-8 text', 'database.not_utf8');
  }
  if (ext === '.json') {
    try {
      JSON.parse(text);
    } catch (e) {
      throw new ContentError(`not valid JSON: ${e.message}`, 'database.bad_json', { detail: String(e.message) });
    }
  } else {
    try {
      yaml.load(text);
    } catch (e) {
      const detail = String(e.reason || e.message);
      throw new ContentError(`not valid YAML: ${detail}${e.mark ? ` (line ${e.mark.line + 1})` : ''}`, 'database.bad_yaml',
        e.mark ? { detail, line: e.mark.line + 1 } : { detail });
    }
  }
}

/**
 * RFC 4180 CSV with the delimiter detected from the first record (',' ';' or tab): quotes are balanced,
 * nothing follows a closing quote but a delimiter or line end, and every non-blank record has the same number
 * of fields as the first one.
 * @param {string} text
 * @returns {{delimiter: string, columns: number, rows: number}}
 * @throws {ContentError}
 */
export function checkCsv(text) {
  const delimiter = detectDelimiter(text);
  let columns = -1;
  let rows = 0;
  let fields = 1;
  let recordLine = 1;
  let line = 1;
  let blank = true; // the current record has no characters so far
  let i = 0;
  const n = text.length;
  const endRecord = () => {
    if (!blank) {
      if (columns === -1) columns = fields;
      else if (fields !== columns) throw new ContentError(`CSV line ${recordLine} has ${fields} columns, expected ${columns} (as in the first line)`, 'database.csv_columns', { line: recordLine, columns: fields, expected: columns });
      rows++;
    }
    fields = 1;
    blank = true;
  };
  while (i < n) {
    const c = text[i];
    if (c === '"') {
      if (!atFieldStart(text, i, delimiter)) throw new ContentError(`CSV line ${line}: quote inside an unquoted field`, 'database.csv_stray_quote', { line });
      blank = false;
      const startLine = line;
      i++;
      for (;;) {
        if (i >= n) throw new ContentError(`CSV line ${startLine}: quoted field is not closed`, 'database.csv_unclosed_quote', { line: startLine });
        if (text[i] === '"') {
          if (text[i + 1] === '"') { i += 2; continue; }
          i++;
          break;
        }
        if (text[i] === '\n') line++;
        i++;
      }
      if (i < n && text[i] !== delimiter && text[i] !== '\n' && text[i] !== '\r') throw new ContentError(`CSV line ${line}: text after a closing quote`, 'database.csv_text_after_quote', { line });
      continue;
    }
    if (c === delimiter) { fields++; blank = false; i++; continue; }
    if (c === '\r' || c === '\n') {
      endRecord();
      if (c === '\r' && text[i + 1] === '\n') i++;
      i++;
      line++;
      recordLine = line;
      continue;
    }
    if (blank && c.trim() === '') {
      const end = blankLineEnd(text, i);
      if (end !== -1) { i = end; continue; }
    }
    blank = false;
    i++;
  }
  endRecord();
  if (rows === 0) throw new ContentError('the CSV file has no rows', 'database.csv_no_rows');
  return { delimiter, columns, rows };
}

function atFieldStart(text, i, delimiter) {
  return i === 0 || text[i - 1] === delimiter || text[i - 1] === '\n' || text[i - 1] === '\r';
}

/** Index of the line end when the rest of the line from i is whitespace, else -1. */
function blankLineEnd(text, i) {
  let j = i;
  for (; j < text.length && text[j] !== '\n' && text[j] !== '\r'; j++) if (text[j].trim() !== '') return -1;
  return j;
}

function detectDelimiter(text) {
  let inQuotes = false;
  const counts = { ',': 0, ';': 0, '\t': 0 };
  for (let i = 0; i < text.length; i++) {
    const c = text[i];
    if (c === '"') inQuotes = !inQuotes;
    else if (!inQuotes && (c === '\n' || c === '\r')) {
      if (counts[','] + counts[';'] + counts['\t'] > 0) break;
    } else if (!inQuotes && c in counts) counts[c]++;
  }
  const [best, count] = Object.entries(counts).sort((a, b) => b[1] - a[1])[0];
  return count > 0 ? best : ',';
}

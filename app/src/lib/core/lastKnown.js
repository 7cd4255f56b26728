/**
 * The last known state of each page, kept in IndexedDB so a page opened offline (or while ROS is
 * unreachable) can still show what it last saw, with its age. Display only: nothing here is ever sent
 * back to the server, and nothing is queued.
 *
 * One object store, keyed by page id (= feature id): { id, data, savedAt, user }. A record saved by
 * another user is not returned, and logout clears the store.
 * Every method resolves (never rejects): without IndexedDB (old browser, private mode) the store is empty.
 */

const STORE = 'pages';

/** @typedef {{ id: string, data: any, savedAt: number, user: string | null }} LastKnownRecord */

export class LastKnownStore {
  /** @type {Promise<IDBDatabase | null> | null} */
  #db = null;

  /**
   * @param {object} [o]
   * @param {IDBFactory | null} [o.idb]  default: the browser's indexedDB
   * @param {string} [o.name]  database name
   * @param {() => number} [o.now]
   */
  constructor(o = {}) {
    this.idb = o.idb !== undefined ? o.idb : safeIndexedDb();
    this.name = o.name ?? 'cell-ui-last-known';
    this.now = o.now ?? Date.now;
  }

  /** @returns {Promise<IDBDatabase | null>} */
  #open() {
    if (this.#db) return this.#db;
    const idb = this.idb;
    this.#db = new Promise((resolve) => {
      if (!idb) return resolve(null);
      try {
        const req = idb.open(this.name, 1);
        req.onupgradeneeded = () => {
          if (!req.result.objectStoreNames.contains(STORE)) req.result.createObjectStore(STORE, { keyPath: 'id' });
        };
        req.onsuccess = () => resolve(req.result);
        req.onerror = () => resolve(null);
        req.onblocked = () => resolve(null);
      } catch {
        resolve(null);
      }
    });
    return this.#db;
  }

  /**
   * @template T
   * @param {IDBTransactionMode} mode
   * @param {(store: IDBObjectStore) => IDBRequest<T>} fn
   * @returns {Promise<T | null>}
   */
  async #run(mode, fn) {
    const db = await this.#open();
    if (!db) return null;
    return new Promise((resolve) => {
      try {
        const tx = db.transaction(STORE, mode);
        const req = fn(tx.objectStore(STORE));
        tx.oncomplete = () => resolve(req.result ?? null);
        tx.onerror = () => resolve(null);
        tx.onabort = () => resolve(null);
      } catch {
        resolve(null);
      }
    });
  }

  /**
   * Keep `data` (structured-clonable: pass $state.snapshot(...) of Svelte state) as the page's last state.
   * @param {string} pageId @param {any} data @param {{ user?: string | null, savedAt?: number }} [o]
   * @returns {Promise<boolean>} whether it was stored
   */
  async save(pageId, data, o = {}) {
    /** @type {LastKnownRecord} */
    const rec = { id: pageId, data, savedAt: o.savedAt ?? this.now(), user: o.user ?? null };
    const r = await this.#run('readwrite', (s) => s.put(rec));
    return r !== null;
  }

  /**
   * @param {string} pageId @param {{ user?: string | null }} [o]  when given, another user's record is ignored
   * @returns {Promise<LastKnownRecord | null>}
   */
  async load(pageId, o = {}) {
    /** @type {LastKnownRecord | null} */
    const rec = await this.#run('readonly', (s) => s.get(pageId));
    if (!rec || typeof rec.savedAt !== 'number') return null;
    if (o.user !== undefined && o.user !== null && rec.user !== o.user) return null;
    return rec;
  }

  /** @param {string} pageId */
  async remove(pageId) {
    await this.#run('readwrite', (s) => s.delete(pageId));
  }

  /** Forget every page (logout). */
  async clear() {
    await this.#run('readwrite', (s) => s.clear());
  }
}

function safeIndexedDb() {
  try {
    return globalThis.indexedDB ?? null;
  } catch {
    return null;
  }
}

/** The app's store. */
export const lastKnown = new LastKnownStore();

/**
 * The ROS graph as the Topics and Nodes views read it (/cell/inspect/graph): the last answer, when it came, and why
 * the last read failed. Each view makes its own and polls it only while it is shown; the answer of an older read
 * that comes after a newer one is dropped.
 */
import { ros } from '../../core/connection.svelte.js';
import { NAMES, GRAPH_TIMEOUT_MS, normaliseGraph } from './logic.js';

export class GraphSource {
  topics = $state.raw(/** @type {import('./logic.js').TopicInfo[]} */ ([]));
  nodes = $state.raw(/** @type {import('./logic.js').NodeInfo[]} */ ([]));
  /** When the graph shown was read (ms since the epoch); null: not yet. */
  at = $state(/** @type {number | null} */ (null));
  loading = $state(false);
  /** Why the last read failed ('' when it did not, or when the link dropped: the not-live notice says so). */
  error = $state('');
  #seq = 0;
  #alive = true;

  refresh = async () => {
    const seq = ++this.#seq;
    this.loading = true;
    try {
      const r = await ros.callService(NAMES.graph.service, NAMES.graph.type, {}, { timeoutMs: GRAPH_TIMEOUT_MS });
      if (!this.#alive || seq !== this.#seq) return;
      const g = normaliseGraph(r);
      this.topics = g.topics;
      this.nodes = g.nodes;
      this.at = Date.now();
      this.error = '';
    } catch (e) {
      if (!this.#alive || seq !== this.#seq) return;
      this.error = ros.state === 'connected' ? (e instanceof Error ? e.message : String(e)) : '';
    } finally {
      if (this.#alive && seq === this.#seq) this.loading = false;
    }
  };

  dispose() {
    this.#alive = false;
  }
}

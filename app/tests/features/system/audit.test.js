import { describe, it, expect, vi, afterEach, beforeEach } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import AuditPanel from '../../../src/lib/features/system/AuditPanel.svelte';
import { auditQuery, pageInfo, filtered, outcomeView, NO_FILTERS, PAGE_SIZE } from '../../../src/lib/features/system/audit.js';

describe('audit.js', () => {
  it('query: filters left out when empty, trimmed; offset and limit', () => {
    expect(auditQuery(NO_FILTERS, 0)).toBe(`offset=0&limit=${PAGE_SIZE}`);
    expect(auditQuery({ user: ' operator ', op: 'database.replace', outcome: 'denied' }, 50, 25)).toBe('user=operator&op=database.replace&outcome=denied&offset=50&limit=25');
    expect(filtered(NO_FILTERS)).toBe(false);
    expect(filtered({ user: '', op: '', outcome: 'ok' })).toBe(true);
  });
  it('position: "26–50 of 230, newest first", and which way one can page', () => {
    expect(pageInfo(230, 25, 25, 25)).toMatchObject({ text: '26–50 of 230, newest first', hasNewer: true, hasOlder: true, newerOffset: 0, olderOffset: 50 });
    expect(pageInfo(30, 25, 5, 25)).toMatchObject({ text: '26–30 of 30, newest first', hasOlder: false });
    expect(pageInfo(0, 0, 0)).toMatchObject({ text: 'No entries', hasNewer: false, hasOlder: false });
  });
  it('outcomes as colour and label', () => {
    expect(outcomeView('ok')).toEqual({ tone: 'ok', label: 'OK' });
    expect(outcomeView('denied')).toEqual({ tone: 'warn', label: 'Denied' });
    expect(outcomeView('failed')).toEqual({ tone: 'danger', label: 'Failed' });
  });
});

describe('AuditPanel', () => {
  /** @type {string[]} */
  let urls;
  const entry = (/** @type {number} */ i) => ({ time: new Date(Date.UTC(2026, 10, 22, 10, 0, 60 - i)).toISOString(), user: i % 2 ? 'operator' : 'admin', role: 'admin', ip: '127.0.0.1', op: i % 3 ? 'login' : 'database.replace', target: 'parts.csv', outcome: i % 4 === 1 ? 'denied' : 'ok', detail: `entry ${i}` });
  beforeEach(() => {
    urls = [];
    vi.stubGlobal('fetch', vi.fn(async (/** @type {string} */ url) => {
      urls.push(url);
      const q = new URL(url, 'http://x').searchParams;
      const offset = Number(q.get('offset')), limit = Number(q.get('limit'));
      const all = Array.from({ length: 60 }, (_, i) => entry(i)).filter((e) => !q.get('user') || e.user === q.get('user')).filter((e) => !q.get('outcome') || e.outcome === q.get('outcome'));
      return new Response(JSON.stringify({ total: all.length, offset, limit, entries: all.slice(offset, offset + limit) }), { status: 200 });
    }));
  });
  afterEach(() => vi.unstubAllGlobals());

  it('newest first, a page at a time, with Older / Newer entries', async () => {
    render(AuditPanel, { users: ['admin', 'operator'] });
    await vi.waitFor(() => expect(screen.getByTestId('audit-position').textContent).toContain('1–25 of 60, newest first'));
    expect(screen.getAllByTestId('audit-entry').length).toBe(25);
    expect(screen.getAllByTestId('audit-entry')[0].textContent).toContain('entry 0');
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Newer entries' })).disabled).toBe(true);
    await fireEvent.click(screen.getByRole('button', { name: 'Older entries' }));
    await vi.waitFor(() => expect(screen.getByTestId('audit-position').textContent).toContain('26–50 of 60'));
    expect(urls.at(-1)).toBe('/api/audit?offset=25&limit=25');
    await fireEvent.click(screen.getByRole('button', { name: 'Older entries' }));
    await vi.waitFor(() => expect(screen.getByTestId('audit-position').textContent).toContain('51–60 of 60'));
    expect(/** @type {HTMLButtonElement} */ (screen.getByRole('button', { name: 'Older entries' })).disabled).toBe(true);
    await fireEvent.click(screen.getByRole('button', { name: 'Newer entries' }));
    await vi.waitFor(() => expect(urls.at(-1)).toBe('/api/audit?offset=25&limit=25'));
  });

  it('filters by user, operation and outcome on Apply filters (from the first page); Clear filters', async () => {
    render(AuditPanel, { users: ['admin', 'operator'] });
    await vi.waitFor(() => expect(screen.getAllByTestId('audit-entry').length).toBe(25));
    await fireEvent.click(screen.getByRole('button', { name: 'Older entries' }));
    await fireEvent.input(screen.getByRole('combobox', { name: 'Filter by user' }), { target: { value: 'operator' } });
    await fireEvent.change(screen.getByRole('combobox', { name: 'Filter by outcome' }), { target: { value: 'denied' } });
    await fireEvent.input(screen.getByRole('combobox', { name: 'Filter by operation' }), { target: { value: 'login' } });
    await fireEvent.click(screen.getByRole('button', { name: 'Apply filters' }));
    await vi.waitFor(() => expect(urls.at(-1)).toBe('/api/audit?user=operator&op=login&outcome=denied&offset=0&limit=25'));
    await vi.waitFor(() => expect(screen.getByTestId('audit-position').textContent).toContain('1–15 of 15, newest first · filtered'));
    for (const e of screen.getAllByTestId('audit-entry')) {
      expect(e.dataset.user).toBe('operator');
      expect(e.textContent).toContain('Denied');
    }
    await fireEvent.click(screen.getByRole('button', { name: 'Clear filters' }));
    await vi.waitFor(() => expect(urls.at(-1)).toBe('/api/audit?offset=0&limit=25'));
  });

  it('403: says the role may not read it', async () => {
    vi.stubGlobal('fetch', vi.fn(async () => new Response('{"error":"no"}', { status: 403 })));
    render(AuditPanel, {});
    expect(await screen.findByText('Your role may not read the audit log.')).toBeTruthy();
  });
});

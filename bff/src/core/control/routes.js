// The control lease over HTTP: who holds it, take (admins may take over), heartbeat, release.
import { Router } from 'express';
import { requireSession } from '../http/guards.js';

/** @param {{lease: import('./lease.js').ControlLease, cell: import('../config/cell-types.js').Cell}} deps */
export function controlRoutes({ lease, cell }) {
  const r = Router();
  const view = (req) => ({ holder: lease.describe(), you: lease.isHolder(req.session) });
  r.get('/api/control', requireSession, (req, res) => res.json(view(req)));
  r.post('/api/control/take', requireSession, (req, res) => {
    const out = lease.take(req.session, { force: req.body?.force === true, mayTakeOver: cell.roles[req.session.role]?.take_over === true });
    if (out.ok === false) return res.status(409).json({ error: out.reason, holder: { username: out.holder.username, role: out.holder.role } });
    res.json(view(req));
  });
  r.post('/api/control/heartbeat', requireSession, (req, res) => {
    if (!lease.heartbeat(req.session)) return res.status(409).json({ error: 'you do not hold control', holder: lease.describe() });
    res.json(view(req));
  });
  r.post('/api/control/release', requireSession, (req, res) => {
    lease.release(req.session);
    res.status(204).end();
  });
  return r;
}

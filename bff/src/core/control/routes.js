// The control lease over HTTP: who holds it, take (admins may take over), heartbeat, release.
import { Router } from 'express';
import { errorBody } from '../http/errors.js';
import { requireSession } from '../http/guards.js';

/**
 * @param {{lease: import('./lease.js').ControlLease, cell: import('../config/cell-types.js').Cell,
 *   mayControl: (role: string) => boolean}} deps  mayControl: the role sends some command that needs the lease (a
 *   role that never moves the robot must not hold control: it would only keep the others from moving it)
 */
export function controlRoutes({ lease, cell, mayControl }) {
  const r = Router();
  const view = (req) => ({ holder: lease.describe(), you: lease.isHolder(req.session) });
  r.get('/api/control', requireSession, (req, res) => res.json(view(req)));
  r.post('/api/control/take', requireSession, (req, res) => {
    if (!mayControl(req.session.role)) return res.status(403).json(errorBody(`role "${req.session.role}" sends no command that moves the robot`, 'control.not_mover', { role: req.session.role }));
    const out = lease.take(req.session, { force: req.body?.force === true, mayTakeOver: cell.roles[req.session.role]?.take_over === true });
    if (out.ok === false) return res.status(409).json({ ...errorBody(out.reason, 'control.held', { user: out.holder.username, role: out.holder.role }), holder: { username: out.holder.username, role: out.holder.role } });
    res.json(view(req));
  });
  r.post('/api/control/heartbeat', requireSession, (req, res) => {
    if (!lease.heartbeat(req.session)) {
      // ended: why this session lost control, when it was the last holder (e.g. it lapsed during a BFF restart)
      const ended = lease.endedFor(req.session);
      return res.status(409).json({ ...errorBody('you do not hold control', 'control.not_holder'), holder: lease.describe(), ...(ended ? { ended } : {}) });
    }
    res.json(view(req));
  });
  r.post('/api/control/release', requireSession, (req, res) => {
    lease.release(req.session);
    res.status(204).end();
  });
  return r;
}

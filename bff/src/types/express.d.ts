// What the BFF adds to Express's request: the session (app.js), the upload spool (database routes).
import 'express-serve-static-core';

declare module 'express-serve-static-core' {
  interface Request {
    session?: { username: string; role: string; sid: string; claims: import('../core/auth/tokens.js').Claims } | null;
    uploadDir?: string;
  }
}

// Home: the overview of the cell (operation mode, connection, who holds control). Reads only what every role
// reads (the operation mode), so it needs no section and names nothing of its own.
import { defineFeature } from '../../core/features/feature.js';

export default defineFeature({ id: 'home', title: 'Home' });

// Which launch files start the ROS side of a cell: the core (cell_bringup/launch/cell.launch: rosbridge, rosapi,
// the operation mode) plus one file per feature whose section the cell file has
// (cell_bringup/launch/features/<id>.launch). A feature's nodes thus start exactly when its section is there,
// and adding a feature adds its launch file, never an edit here or in cell.launch.
import fs from 'node:fs';
import path from 'node:path';

/**
 * @param {Record<string, unknown>} cell the validated cell file
 * @param {string} bringupDir ros_backend/src/cell_bringup
 * @returns {string[]} absolute launch file paths, the core first
 */
export function launchFiles(cell, bringupDir) {
  const features = path.join(bringupDir, 'launch/features');
  const present = fs.existsSync(features) ? fs.readdirSync(features).filter((f) => f.endsWith('.launch')).sort() : [];
  return [
    path.join(bringupDir, 'launch/cell.launch'),
    ...present.filter((f) => cell[f.slice(0, -'.launch'.length)] !== undefined).map((f) => path.join(features, f)),
  ];
}

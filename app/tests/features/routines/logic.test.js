import { setLocale } from '../../../src/lib/paraglide/runtime.js';
import { describe, it, expect } from 'vitest';
import {
  normalizeStep, stepText, actionText, removeStep, moveStep, nameProblem, routineView, routineSummary, runView, toolChoices, poseText,
  toolsOfGroup, robotTopic, ROBOT_TYPE,
} from '../../../src/lib/features/routines/logic.js';

const pose = normalizeStep({ kind: 'pose', pose: [0.4123, -0.12, 0.2305, 0, 3.14, 0], joints: [0, 1, 2, 3, 4, 5] });
const close = normalizeStep({ kind: 'action', tool: 'gripper', action: 'close' });

describe('the draft', () => {
  it('names steps as the log does', () => {
    expect(stepText(pose)).toBe('Pose: x 412.3, y -120.0, z 230.5 mm');
    expect(stepText(close)).toBe('Gripper close');
  });
  it("says why a saved routine cannot be read or run in the user's language", () => {
    const raw = { name: 'a broken', error: 'a broken.json: the file is not valid JSON (Expecting value at line 1, column 1)',
      error_code: 'routines.file_problem', error_params: [
        { key: 'file', value: 'a broken.json' }, { key: 'why', value: 'the file is not valid JSON (Expecting value at line 1, column 1)' },
        { key: 'why.code', value: 'routines.file_not_json' }, { key: 'why.why', value: 'Expecting value' },
        { key: 'why.line', value: '1' }, { key: 'why.column', value: '1' }] };
    expect(routineSummary(routineView(raw))).toBe(raw.error);
    expect(routineSummary(routineView({ name: 'old', error: 'said by an older robot PC' }))).toBe('said by an older robot PC');
    setLocale('es', { reload: false });
    try {
      expect(routineSummary(routineView(raw))).toBe('a broken.json: el archivo no es JSON válido (Expecting value en la línea 1, columna 1)');
    } finally {
      setLocale('en', { reload: false });
    }
  });
  it("names a tool action by the cell file's title in the user's language, as the Manual page's button does", () => {
    const titles = { 'gripper/close': { en: 'Close the gripper', es: 'Cerrar la pinza' }, 'gripper/open': 'Open it' };
    expect(stepText(close, titles)).toBe('Close the gripper');
    expect(actionText('gripper', 'open', titles)).toBe('Open it');
    expect(actionText('gripper', 'check_part', titles)).toBe('Gripper check_part');
    setLocale('es', { reload: false });
    try {
      expect(stepText(close, titles)).toBe('Cerrar la pinza');
    } finally {
      setLocale('en', { reload: false });
    }
  });
  it('deletes and reorders without touching the other steps', () => {
    const s = [pose, close, pose];
    expect(removeStep(s, 1)).toEqual([pose, pose]);
    expect(moveStep(s, 1, -1)).toEqual([close, pose, pose]);
    expect(moveStep(s, 0, -1)).toBe(s);
    expect(moveStep(s, 2, 1)).toBe(s);
  });
});

describe('names', () => {
  it('refuses paths, dot files, empty, too long and duplicates; accepts letters, digits, space - _ .', () => {
    expect(nameProblem('')).toBe('Give the routine a name');
    expect(nameProblem('a/b')).toMatch(/no \//);
    expect(nameProblem('..\\x')).toMatch(/no \//);
    expect(nameProblem('.hidden')).toMatch(/letters/);
    expect(nameProblem('x'.repeat(65))).toBe('At most 64 characters');
    expect(nameProblem('pick 2', ['pick 2'])).toBe("A routine named 'pick 2' exists already");
    expect(nameProblem('Pick_2-b.v1')).toBe('');
    expect(nameProblem('Greifen über')).toMatch(/letters a-z/);
  });
});

describe('saved routines and the run', () => {
  it('summarises steps, and reports an unreadable file by its error', () => {
    const r = routineView({ name: 'p', group: 'arm', tool: 'gripper', steps: [pose, close, pose], modified: { secs: 10, nsecs: 0 } });
    expect(routineSummary(r)).toBe('3 steps: 2 poses, 1 action · arm · gripper');
    expect(r.modified).toBe(10000);
    expect(routineSummary(routineView({ name: 'bad', error: 'not JSON' }))).toBe('not JSON');
  });
  it('run state defaults to idle', () => {
    expect(runView(null).state).toBe('idle');
    expect(runView({ name: 'p', state: 'running', step: 2, total: 3 })).toMatchObject({ state: 'running', step: 2, total: 3 });
  });
  it('offers the section\'s tools with the driver\'s actions', () => {
    expect(toolChoices(['gripper', 'vacuum'], { tools: [{ name: 'gripper', actions: ['open', 'close'] }] }))
      .toEqual([{ name: 'gripper', actions: ['open', 'close'] }, { name: 'vacuum', actions: [] }]);
  });
  it('shows the live pose in mm and rad', () => {
    expect(poseText([0.1, 0.2, 0.3, 0, 3.14159, 0])).toBe('x 100.0  y 200.0  z 300.0 mm · rx 0.000  ry 3.142  rz 0.000 rad');
    expect(poseText(undefined)).toBe('–');
  });
});

describe('motion groups', () => {
  it('each group has its own driver state topic', () => {
    expect(robotTopic('left')).toBe('/cell/manual/left/state');
    expect(ROBOT_TYPE).toBe('cell_msgs/RobotState');
  });
  it('offers only the chosen group\'s tools: the section\'s tool_groups, else the driver\'s ToolInfo.group, else the first group', () => {
    const choices = [{ name: 'gripper', actions: ['open'] }, { name: 'vacuum', actions: ['on'] }, { name: 'lamp', actions: [] }];
    const toolGroups = { gripper: 'left', vacuum: 'right' };
    const groupsAnswer = { groups: [{ name: 'left' }, { name: 'right' }], tools: [{ name: 'lamp', group: 'right' }] };
    expect(toolsOfGroup(choices, 'left', { toolGroups, groupsAnswer }).map((t) => t.name)).toEqual(['gripper']);
    expect(toolsOfGroup(choices, 'right', { toolGroups, groupsAnswer }).map((t) => t.name)).toEqual(['vacuum', 'lamp']);
    expect(toolsOfGroup(choices, 'left', { firstGroup: 'left' }).map((t) => t.name)).toEqual(['gripper', 'vacuum', 'lamp']);
    expect(toolsOfGroup(choices, 'left', { groupsAnswer: { groups: [{ name: 'left' }], tools: [] } }).length).toBe(3);
  });
});

// The operator's language, through the real page and BFF: a browser that asks for Spanish gets the login form and
// the Process page in Spanish, with Spanish number formats and the cell file's Spanish operation titles; a language
// chosen in the user menu is kept with the account, so a new login on another device shows it; the process log is
// said in Spanish too, and so are the robot driver's answers.
import { test, expect } from '@playwright/test';
import { openMenu, users } from '../lib/app.js';
import { simFault, clearSimFault, recorderIdle } from '../lib/ros.js';

test.use({ locale: 'es-ES' });

/** @param {import('@playwright/test').Page} page @param {string} who @param {RegExp | string} submit the Sign in button's name */
async function signIn(page, who, submit) {
  await page.goto('/login');
  await page.getByTestId('login-username').fill(who);
  await page.getByTestId('login-password').fill(users()[who]);
  await page.getByRole('button', { name: submit }).click();
  await expect(page).not.toHaveURL(/\/login/);
}

/** The account back to "the browser's language", so the other specs find their English operator. */
async function forgetLanguage(baseURL) {
  const login = await fetch(`${baseURL}/api/auth/login`, {
    method: 'POST', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ username: 'operator', password: users().operator }),
  });
  const cookie = (login.headers.get('set-cookie') || '').split(';')[0];
  const res = await fetch(`${baseURL}/api/auth/me/preferences`, { method: 'PUT', headers: { cookie, 'content-type': 'application/json' }, body: '{"locale":null}' });
  expect(res.status).toBe(200);
}

test.afterEach(async ({ baseURL }) => forgetLanguage(baseURL));

test('a Spanish browser gets the app in Spanish: login, Process page, numbers and the cell file\'s operation titles', async ({ page }) => {
  await page.goto('/login');
  await expect(page.locator('html')).toHaveAttribute('lang', 'es');
  await expect(page.getByTestId('page-title')).toHaveText('Iniciar sesión');
  await expect(page.getByText('Usuario', { exact: true })).toBeVisible();

  // A wrong password: the BFF's refusal is said in Spanish (its code, not its English sentence).
  await page.getByTestId('login-username').fill('operator');
  await page.getByTestId('login-password').fill('not the password');
  await page.getByRole('button', { name: 'Iniciar sesión' }).click();
  await expect(page.getByTestId('login-error')).toHaveText('Usuario o contraseña incorrectos');

  await signIn(page, 'operator', 'Iniciar sesión');
  await page.goto('/process');
  await expect(page.getByTestId('page-title')).toHaveText('Proceso');
  // The cell file gives the operations a Spanish title; the node still knows them by their names.
  const ops = page.getByTestId('operation');
  await expect(ops.first()).toContainText('Recoger pieza');
  await expect(ops.last()).toContainText('Volver a inicio');
  // A status field: its Spanish label from the cell file, its value with a decimal comma.
  const force = page.getByTestId('status-field').filter({ hasText: 'Fuerza de muñeca Z' });
  await expect(force.getByTestId('status-value')).toHaveText(/^-?\d+,\d+\s*N$/, { timeout: 20_000 });

  // The process node's log in Spanish: its lines come with a code and parameters, not only the English sentence
  // (here: the dry run switched on and off).
  await page.getByRole('button', { name: 'Tomar el control' }).click();
  const dry = page.getByRole('switch', { name: /Ejecución en vacío/ });
  await dry.click();
  await expect(dry).toBeChecked();
  await expect(dry).toBeEnabled();
  const log = page.getByTestId('process-log');
  const lines = log.getByRole('listitem');
  await expect(lines.first()).toContainText('Ejecución en vacío activada: el proceso recorre sus pasos sin mover el robot');
  // One operation, dry: its steps' own texts come from the cell file's Spanish (the node says the English), the
  // pose-table step's note too.
  await page.getByRole('radio', { name: /Recoger pieza/ }).check();
  await page.getByRole('button', { name: 'Ejecutar paso' }).click();
  await expect(lines.first()).toContainText('Hecho: operación «Recoger pieza» hecha', { timeout: 30_000 });
  await expect(log).toContainText('Ejecución en vacío: Comprobar que la pieza está en la pinza');
  await expect(log).toContainText('Ejecución en vacío: Levantar la pieza');
  await expect(log).toContainText(/Ejecución en vacío: Mover a part \d \(aproximación\)/);
  await expect(page.getByTestId('process-state')).toHaveText('En reposo');
  await dry.click();
  await expect(dry).not.toBeChecked();
  await expect(lines.first()).toContainText('Ejecución en vacío desactivada: el proceso mueve el robot');
  await page.getByRole('button', { name: 'Liberar el control' }).click();
});

test("a Spanish operator reads the cell's alarms in Spanish: a device's from the cell file, the robot's by its code", async ({ page }) => {
  await signIn(page, 'operator', 'Iniciar sesión');
  await page.goto('/alarms');
  await simFault('door_open');
  try {
    // The sim's door writes its fault in English; the cell file's alarms.texts says it in Spanish.
    const door = page.locator('[data-testid="alarm"][data-alarm="device.door_open"]');
    await expect(door.locator('p.text')).toHaveText('Puerta de la célula abierta: parada de salvaguarda hasta que se cierre', { timeout: 20_000 });
    // The alarms node's own alarm comes with its code and group: the app's Spanish catalogue says it.
    const stop = page.locator('[data-testid="alarm"][data-alarm="robot.arm.safeguard_stop"]');
    await expect(stop.locator('p.text')).toHaveText('Robot arm: parada de salvaguarda: un resguardo (puerta, cortina óptica) está abierto');
    await expect(page.getByTestId('alarm-banner')).toContainText(/Puerta de la célula abierta|parada de salvaguarda: un resguardo/);
  } finally {
    await clearSimFault('device.door_open');
    await recorderIdle();
  }
});

test("the robot driver's answers in Spanish: a move's result on the Manual page, by its code", async ({ page }) => {
  await signIn(page, 'admin', 'Iniciar sesión');
  await page.goto('/manual');
  await page.getByRole('button', { name: 'Tomar el control' }).click();
  await page.getByRole('combobox', { name: 'Configuración con nombre' }).selectOption('home');
  await page.getByRole('button', { name: 'Mover a la configuración' }).click();
  // The driver says "arrived at home" with the code manual.arrived_at: the button's result and the state's last
  // message are both said in Spanish.
  await expect(page.getByTestId('move-named-feedback')).toContainText('se alcanzó home', { timeout: 30_000 });
  await expect(page.getByTestId('manual-message')).toContainText('se alcanzó home');
  // A tool action's button is the cell file's Spanish title, and the driver's answer names it so.
  await page.getByRole('button', { name: 'Abrir pinza' }).click();
  await expect(page.getByTestId('tool-gripper-open-feedback')).toContainText('Abrir pinza: listo', { timeout: 15_000 });
  await page.getByRole('button', { name: 'Liberar el control' }).click();
});

test('a language chosen in the user menu is kept with the account: a new login elsewhere shows it', async ({ page, browser }) => {
  await signIn(page, 'operator', 'Iniciar sesión');
  await page.goto('/process');
  await expect(page.getByTestId('page-title')).toHaveText('Proceso');
  await openMenu(page);
  const settings = page.getByTestId('display-settings');
  await settings.getByText('Pantalla e idioma').click();
  await settings.getByRole('combobox', { name: 'Idioma' }).selectOption('fi');
  // The page is drawn again in Finnish.
  await expect(page.getByTestId('page-title')).toHaveText('Prosessi');
  await expect(page.locator('html')).toHaveAttribute('lang', 'fi');

  // Another device, whose browser asks for Spanish: the account's Finnish wins after the login.
  const other = await browser.newContext({ locale: 'es-ES' });
  try {
    const p2 = await other.newPage();
    await signIn(p2, 'operator', 'Iniciar sesión');
    // The page after the login is already drawn in the account's language.
    await expect(p2.locator('html')).toHaveAttribute('lang', 'fi');
    await p2.goto('/process');
    await expect(p2.getByTestId('page-title')).toHaveText('Prosessi');
    await expect(p2.getByTestId('operation').first()).toContainText('Poimi kappale');
    // Logged out, the login page follows that browser again.
    await openMenu(p2);
    await p2.getByRole('button', { name: 'Kirjaudu ulos' }).click();
    await p2.reload();
    await expect(p2.getByTestId('page-title')).toHaveText('Iniciar sesión');
  } finally {
    await other.close();
  }
});

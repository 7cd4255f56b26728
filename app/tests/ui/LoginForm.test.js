import { describe, it, expect, vi } from 'vitest';
import { render, screen, fireEvent } from '@testing-library/svelte';
import LoginForm from '../../src/lib/ui/LoginForm.svelte';
import { Session } from '../../src/lib/core/session.svelte.js';

describe('LoginForm', () => {
  it('shows the server error on 401 and does not report success', async () => {
    const fetchMock = vi.fn(async (/** @type {any} */ _url, /** @type {any} */ _init) => new Response(JSON.stringify({ error: 'Invalid user name or password' }), { status: 401 }));
    vi.stubGlobal('fetch', fetchMock);
    const session = new Session({ storage: null });
    const onSuccess = vi.fn();
    render(LoginForm, { login: (u, p) => session.login(u, p), onSuccess });

    expect(screen.queryByTestId('login-error')).toBeNull();
    await fireEvent.input(screen.getByTestId('login-username'), { target: { value: 'ann' } });
    await fireEvent.input(screen.getByTestId('login-password'), { target: { value: 'wrong' } });
    await fireEvent.click(screen.getByTestId('login-submit'));

    const err = await screen.findByTestId('login-error');
    expect(err.textContent).toContain('Invalid user name or password');
    expect(onSuccess).not.toHaveBeenCalled();
    expect(fetchMock).toHaveBeenCalledTimes(1);
    expect(JSON.parse(fetchMock.mock.calls[0][1]?.body)).toEqual({ username: 'ann', password: 'wrong' });
    // The password field is cleared after a failed attempt.
    expect(/** @type {HTMLInputElement} */ (screen.getByTestId('login-password')).value).toBe('');
    vi.unstubAllGlobals();
  });

  it('shows the throttling message on 429', async () => {
    const login = vi.fn(async () => ({ ok: false, error: 'Too many attempts' }));
    render(LoginForm, { login });
    await fireEvent.input(screen.getByTestId('login-username'), { target: { value: 'ann' } });
    await fireEvent.input(screen.getByTestId('login-password'), { target: { value: 'x' } });
    await fireEvent.click(screen.getByTestId('login-submit'));
    expect((await screen.findByTestId('login-error')).textContent).toContain('Too many attempts');
  });

  it('calls onSuccess after a good login', async () => {
    const login = vi.fn(async () => /** @type {const} */ ({ ok: true }));
    const onSuccess = vi.fn();
    render(LoginForm, { login, onSuccess });
    await fireEvent.input(screen.getByTestId('login-username'), { target: { value: ' ann ' } });
    await fireEvent.input(screen.getByTestId('login-password'), { target: { value: 'pw' } });
    await fireEvent.click(screen.getByTestId('login-submit'));
    await vi.waitFor(() => expect(onSuccess).toHaveBeenCalledTimes(1));
    expect(login).toHaveBeenCalledWith('ann', 'pw');
    expect(screen.queryByTestId('login-error')).toBeNull();
  });

  it('asks for both fields instead of sending an empty login', async () => {
    const login = vi.fn();
    render(LoginForm, { login });
    await fireEvent.click(screen.getByTestId('login-submit'));
    expect(login).not.toHaveBeenCalled();
    expect(screen.getByTestId('login-error')).toBeTruthy();
  });
});

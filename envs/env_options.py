"""How the training and evaluation scripts build an env: the registered task behind the options' wrappers.

:class:`EnvOptions` holds every option that shapes the env a policy is trained or evaluated on: ``gym.make``'s
keyword arguments, the wrappers that are part of the policy (``--valve-share``, ``--action-offset``,
``--residual``, ``--touch-memory``, ``--privileged-critic``, ``--frame-stack``: training and evaluation alike) and
the training aids (``--scripted-start``, ``--light-bias``, ``--crush-charge``, ``--step-charge``,
``--crush-margin``: training only; evaluation runs the task, which :meth:`EnvOptions.evaluation` gives).
:func:`make_env` builds the env they describe; ``<algo>_eval.json`` records them through :meth:`EnvOptions.record`.

The wrappers, innermost first: ``LightBias``, ``CrushCharge``, ``StepCharge``, ``CrushMargin``, ``ScriptedStart``,
``ValveShare``, ``ScriptedResidual``, ``TouchMemory``, ``ActionOffset``, ``PrivilegedObservation``,
``FrameStackObservation``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

__all__ = ["EnvOptions", "check_training_env", "make_env"]


@dataclass(frozen=True)
class EnvOptions:
    """The options that shape a training or evaluation env (module docstring).

    Attributes
    ----------
    env_kwargs : dict
        ``gym.make``'s keyword arguments (an ablation; empty: the registered task).
    action_offset : sequence of float or None
        The env performs ``clip(action + offset)``, :class:`~simgrip.envs.action_offset.ActionOffset`.
    frame_stack : int or None
        The observation becomes the last ``frame_stack`` observations, oldest first (2 or more; 1 is no stack).
    residual : sequence of str or None
        Action names the task's scripted observation-only controller drives, the action added to it
        (:class:`~simgrip.envs.scripted_residual.ScriptedResidual`; part of the policy).
    residual_alone : bool
        With ``residual``: the controller drives those actions alone and the policy acts on the others only.
    valve_share : float or None
        The policy's curvature rate times it before the valve (:class:`~simgrip.envs.valve_share.ValveShare`, a
        restrictor; part of the policy): it closes at most that share of the valve's rate.
    touch_memory : bool
        The observation gains the first touch's memory (:class:`~simgrip.envs.touch_memory.TouchMemory`; part of
        the policy).
    privileged_critic : bool
        The observation gains the hidden entries PPO's value function reads and its policy does not
        (:class:`~simgrip.envs.privileged_critic.PrivilegedObservation`; training and evaluation alike).
    scripted_start : float or None
        Training only: that share of the resets starts part-way through the scripted controller's episode.
    light_bias : float or None
        Training only: that share of the resets draws its mass from the light end of the range.
    crush_charge : (float, int) or None
        Training only: ``(charge, start)``, every crush's reward lowered by ``charge`` from step ``start`` on.
    step_charge : float or None
        Training only: every step's reward lowered by it.
    crush_margin : float or None
        Training only: every step's reward lowered by it times how near its largest finger force came to the
        hidden crush limit.
    """

    env_kwargs: dict = field(default_factory=dict)
    action_offset: tuple | None = None
    frame_stack: int | None = None
    residual: tuple | None = None
    residual_alone: bool = False
    valve_share: float | None = None
    touch_memory: bool = False
    privileged_critic: bool = False
    scripted_start: float | None = None
    light_bias: float | None = None
    crush_charge: tuple | None = None
    step_charge: float | None = None
    crush_margin: float | None = None

    @classmethod
    def from_args(cls, args) -> "EnvOptions":
        """The options of the parsed arguments of ``train_sb3.py``, ``rl_baselines.py`` or
        ``evaluate_policy.py`` (an option a script lacks is None; ``--crush-charge`` with ``--crush-charge-from``,
        default step 0)."""
        def get(name):
            return getattr(args, name, None)

        charge = get("crush_charge")
        return cls(env_kwargs=dict(get("env_kwargs") or {}), action_offset=_tuple(get("action_offset")),
                   frame_stack=get("frame_stack"), residual=_tuple(get("residual")),
                   residual_alone=bool(get("residual_alone")), valve_share=get("valve_share"),
                   touch_memory=bool(get("touch_memory")),
                   privileged_critic=bool(get("privileged_critic")),
                   scripted_start=get("scripted_start"), light_bias=get("light_bias"),
                   crush_charge=None if charge is None else (charge, get("crush_charge_from") or 0),
                   step_charge=get("step_charge"), crush_margin=get("crush_margin"))

    def evaluation(self) -> "EnvOptions":
        """These options without the training aids: the env a policy trained behind them is evaluated on."""
        return replace(self, scripted_start=None, light_bias=None, crush_charge=None, step_charge=None,
                       crush_margin=None)

    def shaped(self) -> bool:
        """Whether any option shapes the env (False: :func:`make_env` gives the registered task itself)."""
        return self != EnvOptions()

    def record(self) -> tuple[dict, list[str]]:
        """What ``<algo>_eval.json`` records of the options: its keys (``env_kwargs``, ``action_offset``,
        ``residual``, ``residual_alone`` (only where true), ``valve_share``, ``touch_memory`` and
        ``privileged_critic`` (only where true), ``frame_stack``, ``scripted_start``, ``light_bias``,
        ``crush_charge`` as ``{"charge", "start"}``, ``step_charge``, ``crush_margin``; each only where set) and the
        wrappers named, in that order."""
        keys, wrappers = {}, []
        if self.env_kwargs:
            keys["env_kwargs"] = dict(self.env_kwargs)
        if self.action_offset is not None:
            keys["action_offset"] = [float(x) for x in self.action_offset]
            wrappers.append(f"ActionOffset({keys['action_offset']})")
        if self.residual is not None:
            keys["residual"] = list(self.residual)
            if self.residual_alone:
                keys["residual_alone"] = True
            wrappers.append(f"ScriptedResidual({list(self.residual)}{', alone' if self.residual_alone else ''})")
        if self.valve_share is not None:
            keys["valve_share"] = float(self.valve_share)
            wrappers.append(f"ValveShare({keys['valve_share']!r})")
        if self.touch_memory:
            keys["touch_memory"] = True
            wrappers.append("TouchMemory")
        if self.privileged_critic:
            keys["privileged_critic"] = True
            wrappers.append("PrivilegedObservation (the critic's)")
        if self.frame_stack is not None and self.frame_stack > 1:
            keys["frame_stack"] = int(self.frame_stack)
            wrappers.append(f"FrameStackObservation({int(self.frame_stack)})")
        for name, wrapper in (("scripted_start", "ScriptedStart"), ("light_bias", "LightBias")):
            if getattr(self, name) is not None:
                keys[name] = float(getattr(self, name))
                wrappers.append(f"{wrapper}({keys[name]!r}) in training")
        if self.crush_charge is not None:
            charge, start = float(self.crush_charge[0]), int(self.crush_charge[1])
            keys["crush_charge"] = {"charge": charge, "start": start}
            wrappers.append(f"CrushCharge({charge!r}, from step {start}) in training")
        for name, wrapper in (("step_charge", "StepCharge"), ("crush_margin", "CrushMargin")):
            if getattr(self, name) is not None:
                keys[name] = float(getattr(self, name))
                wrappers.append(f"{wrapper}({keys[name]!r}) in training")
        return keys, wrappers


def _tuple(value):
    return None if value is None else tuple(value)


def make_env(env_id: str, options: EnvOptions | None = None):
    """The env of ``env_id`` (a registered id, or a retired one of ``simgrip.envs.RETIRED`` through its spec) made
    with ``options.env_kwargs`` and behind the options' wrappers (:class:`EnvOptions`; None: the task itself):
    what the training and evaluation scripts build and check their options with.  With ``frame_stack`` 2 or
    more the observation has shape ``(frame_stack, n)``, after ``reset`` the first one repeated.

    Raises ValueError naming the option: ``--env-kwargs`` when the env does not take ``env_kwargs`` or refuses a
    value, ``--action-offset`` when the offset does not fit its action space (the env is closed first),
    ``--frame-stack`` when it is not a whole number >= 1 (checked before any env is made) or is longer than the
    env's episodes, ``--scripted-start`` when it is not a probability or the env has no scripted controller,
    ``--light-bias`` when it is not a probability or the env is not a fragile task (the env is closed first),
    ``--residual`` when a name is not one of the env's actions, the env has no scripted controller, or
    ``scripted_start`` is given too, ``--residual-alone`` without ``--residual`` or where it names every action,
    ``--valve-share`` when it is not in ``(0, 1]``, the env has no valve or a residual drives its curvature,
    ``--touch-memory`` when the env does not observe the curvature, the finger forces and the lift,
    ``--privileged-critic`` when the env is not a fragile task or with ``--frame-stack``,
    ``--crush-charge``, ``--step-charge`` and ``--crush-margin`` when the env is
    not a fragile task (the env is closed first)."""
    import json

    import gymnasium as gym

    from simgrip.envs import make_spec

    o = EnvOptions() if options is None else options
    if o.frame_stack is not None and (isinstance(o.frame_stack, bool) or not isinstance(o.frame_stack, int)
                                      or o.frame_stack < 1):
        raise ValueError(f"--frame-stack: a whole number >= 1, got {o.frame_stack!r}")
    if o.residual is not None and o.scripted_start is not None:
        raise ValueError("--residual: not with --scripted-start (the controller would start mid-episode)")
    if o.residual_alone and o.residual is None:
        raise ValueError("--residual-alone: needs --residual (the actions the controller drives alone)")
    kwargs = dict(o.env_kwargs or {})
    try:
        env = gym.make(make_spec(env_id), **kwargs)
    except (TypeError, ValueError) as e:
        raise ValueError(f"--env-kwargs: {env_id} does not take {json.dumps(kwargs)}: {e}") from None
    if o.light_bias is not None:
        from simgrip.envs.light_bias import LightBias

        env = _wrap_or_close(env, LightBias, o.light_bias, "--light-bias")
    if o.crush_charge is not None:
        from simgrip.envs.crush_charge import CrushCharge

        env = _wrap_or_close(env, lambda e, v: CrushCharge(e, *v), o.crush_charge, "--crush-charge")
    if o.step_charge is not None:
        from simgrip.envs.step_charge import StepCharge

        env = _wrap_or_close(env, StepCharge, o.step_charge, "--step-charge")
    if o.crush_margin is not None:
        from simgrip.envs.crush_margin import CrushMargin

        env = _wrap_or_close(env, CrushMargin, o.crush_margin, "--crush-margin")
    if o.scripted_start is not None:
        from simgrip.envs.scripted_start import ScriptedStart

        env = _wrap_or_close(env, ScriptedStart, o.scripted_start, "--scripted-start")
    if o.valve_share is not None:
        from simgrip.envs.valve_share import ValveShare

        names = tuple(getattr(env.unwrapped, "action_names", ()))
        if o.residual is not None and names and names[0] in o.residual:
            env.close()
            raise ValueError(f"--valve-share: not with a residual on the curvature ({names[0]}): the scripted "
                             "controller's command would be cut too")
        env = _wrap_or_close(env, ValveShare, o.valve_share, "--valve-share")
    if o.residual is not None:
        from simgrip.envs.scripted_residual import ScriptedResidual

        env = _wrap_or_close(env, lambda e, v: ScriptedResidual(e, v, alone=o.residual_alone), o.residual,
                             "--residual-alone" if o.residual_alone else "--residual")
    if o.touch_memory:
        from simgrip.envs.touch_memory import TouchMemory

        env = _wrap_or_close(env, lambda e, _: TouchMemory(e), True, "--touch-memory")
    if o.action_offset is not None:
        from simgrip.envs.action_offset import ActionOffset

        env = _wrap_or_close(env, ActionOffset, o.action_offset, "--action-offset")
    if o.privileged_critic:
        from simgrip.envs.privileged_critic import PrivilegedObservation

        if o.frame_stack is not None and o.frame_stack > 1:
            env.close()
            raise ValueError("--privileged-critic: not with --frame-stack (the policy's view hides the last entries "
                             "of one observation)")
        env = _wrap_or_close(env, lambda e, _: PrivilegedObservation(e), True, "--privileged-critic")
    if o.frame_stack is not None and o.frame_stack > 1:
        longest = getattr(env.spec, "max_episode_steps", None)
        if longest is not None and o.frame_stack > longest:
            env.close()
            raise ValueError(f"--frame-stack: at most the episode's {longest} steps (a longer stack only repeats "
                             f"the first observation), got {o.frame_stack}")
        env = gym.wrappers.FrameStackObservation(env, o.frame_stack)
    return env


def check_training_env(args) -> None:
    """Build and close the training env that the parsed options of ``train_sb3.py`` / ``rl_baselines.py`` describe
    (:func:`make_env` with :meth:`EnvOptions.from_args`), so that an option the env refuses is named before any
    training starts; nothing is built when no option shapes the env.  Raises :func:`make_env`'s ValueError, naming
    the option."""
    options = EnvOptions.from_args(args)
    if options.shaped():
        make_env(args.env, options).close()


def _wrap_or_close(env, wrapper, value, option: str):
    """``wrapper(env, value)``; on its ValueError ``env`` is closed and the error re-raised naming ``option``."""
    try:
        return wrapper(env, value)
    except ValueError as e:
        env.close()
        raise ValueError(f"{option}: {e}") from None

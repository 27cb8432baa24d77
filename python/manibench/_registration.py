"""The environment ids manibench registers with gymnasium on import (where
gymnasium is importable): every task, and every fixed-object id as
`manibench objects` names them (<Task>_<object>-v<N> for each object of
either split, and for each articulated object whose target links are
objects <object>_link_<k>), as ManiSkill registers them."""

from __future__ import annotations

import re
from typing import Callable, Iterable

from . import _core

_VERSIONED = re.compile(r"(?P<base>.+)-v(?P<version>\d+)")


def list_fixed_object_ids(task: str, objects: Iterable[str]) -> list[str]:
    """The fixed-object ids of `task` for `objects` (train then test ids):
    each object's, preceded by its articulated object's (the id before
    "_link_") the first time that appears."""
    match = _VERSIONED.fullmatch(task)
    if match is None:  # makeFixedObjectId: only names ending in -v<N>
        return []
    ids = []
    for object_id in objects:
        at = object_id.rfind("_link_")
        for spec in ([object_id[:at]] if at >= 0 else []) + [object_id]:
            env_id = f"{match['base']}_{spec}-v{match['version']}"
            if env_id not in ids:
                ids.append(env_id)
    return ids


def list_env_ids(tasks: Iterable[str] | None = None) -> list[str]:
    """Every task and its fixed-object ids (one environment per task is made
    to list its objects)."""
    ids = []
    for task in _core.list_tasks() if tasks is None else tasks:
        core = _core.Environment(task, [], [], True, False)
        try:
            objects = list(dict.fromkeys(core.list_objects("train") + core.list_objects("test")))
        finally:
            core.close()
        ids += [task] + list_fixed_object_ids(task, objects)
    return ids


def register_all(register: Callable[..., None], registered: Iterable[str]) -> list[str]:
    """Calls register(id=..., entry_point=..., vector_entry_point=...,
    kwargs=...) as gymnasium.register takes them, for every id of
    list_env_ids() not in `registered`; returns the ids it registered."""
    known = set(registered)
    done = []
    for env_id in list_env_ids():
        if env_id in known:
            continue
        register(id=env_id, entry_point="manibench.env:ManibenchEnv",
                 vector_entry_point="manibench.vector:make_vec", kwargs={"env_id": env_id})
        done.append(env_id)
    return done

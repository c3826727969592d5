"""The offline kernel count's reading of an optimized HLO module: which computations run as
control flow (entry, loop body and condition, the branches of a conditional), and that only
their own instructions count, not those inside the fusions they launch."""

import jax
import jax.numpy as jnp
import numpy as np

from benchmarks.offline_kernels import control_computations, launches


def looped_switch(x, k):
    def body(i, acc):
        branches = [lambda a: a, lambda a: jnp.sin(a) * 2.0, lambda a: jnp.cos(a) + a * a]
        return jax.lax.switch((k + i) % 3, branches, acc)
    return jax.lax.fori_loop(0, k, body, x)


def test_roles_and_launches_of_a_looped_switch(rng):
    x = jnp.asarray(rng.normal(size=(256,)).astype(np.float32))
    text = jax.jit(looped_switch).lower(x, jnp.int32(4)).compile().as_text()
    roles = control_computations(text)
    kinds = sorted(roles.values())
    assert kinds.count("entry") == 1, roles
    assert kinds.count("while-body") == 1 and kinds.count("while-condition") == 1, roles
    assert kinds.count("branch") == 3, roles
    rows = launches(text)
    assert {name for _, name, _ in rows} == set(roles), (rows, roles)
    fused = [name for _, name, _ in rows if name.startswith(("fused", "wrapped"))]
    assert not fused, f"fused computations listed as control flow: {fused}"
    branches = [k for _, n, k in rows if roles[n] == "branch"]
    # The identity branch computes nothing (XLA may copy its operand); the two others each
    # launch their arithmetic as a fusion.
    computing = [k for k in branches if k["fusion"]]
    assert len(computing) == 2, branches
    assert [set(k) <= {"copy"} for k in branches].count(True) == 1, branches
    assert all(not {"while", "conditional", "parameter"} & set(k) for _, _, k in rows), rows

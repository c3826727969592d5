"""Object-space shading: what the store's bookkeeping costs, in bits per shadel, counted from
the arrays the pipeline actually holds (their sizes and dtypes, static under jit).

- the ID map: the owning triangle of every virtual shadel (``ShadeSheet.owner``);
- the per-chunk metadata: what each virtual chunk is (object, level, position: the sheet's
  ``chunk_*`` arrays), where it lives (the page table, ``Allocation.page``) and, per store
  slot, which chunk fills it (``Allocation.slot_chunk``).

Both are divided by the virtual shadels they describe (every shadel of every MIP level of
every object: ``n_chunks * 64``), the unit of Baker and Jarzynski's (EGSR 2022) ~1.5 bits per
shadel. Beside them: the full MIP chain's size over level 0 (``mip_chain_memory``, GDC 2016's
1.25-1.33x) is in object_space's counts already.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxrender.pipelines.os_sheet import LANES, ShadeSheet


def bits(*arrays) -> int:
    """Total bits of ``arrays`` (concrete or traced: size and dtype are static)."""
    return sum(int(a.size) * jnp.dtype(a.dtype).itemsize * 8 for a in arrays)


def memory_counts(sheet: ShadeSheet, page, slot_chunk) -> dict:
    """{id_map_bits_per_shadel, chunk_metadata_bits_per_shadel, virtual_shadels}: float32 /
    int32 constants of the sheet and the allocation arrays ``page`` and ``slot_chunk``."""
    shadels = max(sheet.n_chunks * LANES, 1)
    meta = bits(sheet.chunk_obj, sheet.chunk_level, sheet.chunk_cx, sheet.chunk_cy, page,
                slot_chunk)
    return {"id_map_bits_per_shadel": jnp.float32(bits(sheet.owner) / shadels),
            "chunk_metadata_bits_per_shadel": jnp.float32(meta / shadels),
            "virtual_shadels": jnp.int32(sheet.n_chunks * LANES)}


__all__ = ["bits", "memory_counts"]

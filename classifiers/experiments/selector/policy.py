"""Permutation-invariant actor-critic for picking one grip among K candidates.

The observation is a set: ``{"features": (K, F), "mask": (K,)}``, and in the retry setting
(``GripSelect-v0`` with ``max_attempts > 1``) ``"failed": (K,)`` too, the slots tried and failed
this episode. :class:`CandidateSetPolicy` is a
:class:`~sb3_contrib.common.maskable.policies.MaskableActorCriticPolicy` whose parts are
swapped through SB3's own extension points:

- ``features_extractor`` = :class:`CandidateSetExtractor`: packs the dict into one tensor
  ``(B, K * (F + 1))`` (each candidate's features followed by its mask bit), or
  ``(B, K * (F + 2))`` with the failed bit last when the observation has ``failed``; no
  learning;
- ``mlp_extractor`` = :class:`CandidateSetNetwork` (the ``_build_mlp_extractor`` hook):
  ONE shared scorer MLP maps each candidate's own feature vector to a logit, so
  ``latent_pi`` is the ``(B, K)`` vector of scores; a second shared encoder embeds each
  candidate for the critic and pools over valid candidates (masked mean and max), so
  ``latent_vf`` does not depend on candidate order. With ``context="pool"`` the scorer also
  sees the set: each candidate's embedding is joined with the masked mean and max of all valid
  candidates' embeddings before the last layers; with ``context="attention"`` each candidate's
  embedding attends to the valid candidates (one multi-head self-attention layer, padded slots
  masked out, residual) before the score head;
- with ``failed``, a third shared encoder embeds each failed candidate and pools over the
  failed ones (masked mean and max, and the number failed): this summary of what the episode's
  draw defeated is joined to every candidate's input to the scorer and to the critic's pooled
  summary, so a second pick can condition on the grips that dropped (a failed slot is masked,
  so without it the policy would see a failure only as a missing candidate);
- ``action_net`` = identity, so the categorical's logits are the scores themselves.
  MaskablePPO sets invalid slots to -inf: the action distribution is the masked softmax.

Permuting the candidates (and the mask with them) permutes the action probabilities the same
way and leaves the value unchanged; any number of valid candidates up to K works. A policy
whose observation has no ``failed`` builds no failure encoder: its parameters, and so a zip
saved from a one-attempt run, are those of the two-key policy.
"""

from __future__ import annotations

from itertools import pairwise
from typing import Any, Literal

import torch as th
from gymnasium import spaces
from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from stable_baselines3.common.type_aliases import Schedule
from torch import nn

#: How the actor's scorer sees the other candidates: not at all, pooled, or by attention.
CONTEXTS: tuple[str, ...] = ("none", "pool", "attention")
Context = Literal["none", "pool", "attention"]
ATTENTION_HEADS = 4


def _candidate_shape(observation_space: spaces.Space) -> tuple[int, int]:
    if not isinstance(observation_space, spaces.Dict) or {"features", "mask"} - set(
        observation_space.spaces
    ):
        raise ValueError(
            f"observation space must be a Dict with 'features' and 'mask', got {observation_space}"
        )
    shape = observation_space["features"].shape
    if shape is None or len(shape) != 2:
        raise ValueError(f"'features' must have shape (K, F), got {shape}")
    return int(shape[0]), int(shape[1])


def reads_failed(observation_space: spaces.Space) -> bool:
    """Whether the observation says which slots failed (``GripSelect-v0``'s retry setting)."""
    return isinstance(observation_space, spaces.Dict) and "failed" in observation_space.spaces


class CandidateSetExtractor(BaseFeaturesExtractor):
    """Pack ``{"features": (B, K, F), "mask": (B, K)[, "failed": (B, K)]}`` into
    ``(B, K * (F + 1))`` (or ``(B, K * (F + 2))`` with ``failed``).

    Each candidate keeps its own row (features, mask bit, then failed bit); nothing is learnt
    here. ``read_failed=False`` leaves ``failed`` out even when the observation has it.
    """

    def __init__(self, observation_space: spaces.Dict, read_failed: bool | None = None) -> None:
        n_candidates, n_features = _candidate_shape(observation_space)
        self.failed = reads_failed(observation_space) and read_failed is not False
        bits = 2 if self.failed else 1
        super().__init__(observation_space, features_dim=n_candidates * (n_features + bits))
        self.n_candidates = n_candidates
        self.n_features = n_features

    def forward(self, observations: dict[str, th.Tensor]) -> th.Tensor:
        features = observations["features"].float()
        shape = (features.shape[0], self.n_candidates, 1)
        columns = [features, observations["mask"].float().reshape(shape)]
        if self.failed:
            columns.append(observations["failed"].float().reshape(shape))
        return th.cat(columns, dim=-1).flatten(start_dim=1)


def _mlp(sizes: list[int], activation_fn: type[nn.Module]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for n_in, n_out in pairwise(sizes):
        layers += [nn.Linear(n_in, n_out), activation_fn()]
    return nn.Sequential(*layers)


def masked_pool(embeddings: th.Tensor, mask: th.Tensor) -> th.Tensor:
    """Concatenate the masked mean and masked max of ``(B, K, H)`` over valid slots → ``(B, 2H)``.

    Rows with no valid candidate pool to zeros.
    """
    valid = mask.unsqueeze(-1) > 0.5
    count = valid.sum(dim=1).clamp(min=1)
    mean = th.where(valid, embeddings, 0.0).sum(dim=1) / count
    lowest = th.finfo(embeddings.dtype).min
    peak = th.where(valid, embeddings, lowest).amax(dim=1)
    peak = th.where(valid.any(dim=1), peak, 0.0)
    return th.cat([mean, peak], dim=-1)


class CandidateSetNetwork(nn.Module):
    """Shared per-candidate actor scorer and pooled critic encoder (SB3 ``mlp_extractor``).

    :param n_candidates: K, slots in the observation.
    :param n_features: F, features per candidate.
    :param pi_arch: hidden sizes of the shared scorer (ends in one logit per candidate).
    :param vf_arch: hidden sizes of the shared critic encoder (pooled mean and max).
    :param context: ``"none"`` (each score from its own candidate only), ``"pool"`` (the first
        hidden layer's embedding joined with its masked mean and max over the set) or
        ``"attention"`` (that embedding passed through one masked self-attention layer).
    :param failed: whether each packed row ends in a failed bit (the retry setting): then a
        shared failure encoder (one hidden layer, ``pi_arch[0]`` wide, else ``vf_arch[0]``)
        embeds each failed candidate's features, and the masked mean and max over the failed
        candidates, with their number, are joined to every candidate's scorer input and to the
        critic's summary (:meth:`failure_summary`).
    """

    def __init__(
        self,
        n_candidates: int,
        n_features: int,
        pi_arch: list[int],
        vf_arch: list[int],
        activation_fn: type[nn.Module] = nn.Tanh,
        context: Context = "none",
        failed: bool = False,
    ) -> None:
        super().__init__()
        if not vf_arch:
            raise ValueError("vf_arch needs at least one hidden layer to pool")
        if context not in CONTEXTS:
            raise ValueError(f"context must be one of {CONTEXTS}, got {context!r}")
        if context != "none" and not pi_arch:
            raise ValueError(f"context {context!r} needs at least one hidden layer in pi_arch")
        self.n_candidates = n_candidates
        self.n_features = n_features
        self.context = context
        self.failed = failed
        summary = 0
        if failed:
            failure_width = (pi_arch or vf_arch)[0]
            self.failure_encoder = _mlp([n_features, failure_width], activation_fn)
            summary = 2 * failure_width + 1
        scorer_in = n_features + summary
        if context == "none":
            self.scorer_body = _mlp([scorer_in, *pi_arch], activation_fn)
            width = ([scorer_in, *pi_arch])[-1]
        else:
            self.scorer_embed = _mlp([scorer_in, pi_arch[0]], activation_fn)
            joined = 3 * pi_arch[0] if context == "pool" else pi_arch[0]
            if context == "attention":
                self.attention = nn.MultiheadAttention(pi_arch[0], _heads(pi_arch[0]),
                                                       batch_first=True)  # fmt: skip
            self.scorer_body = _mlp([joined, *pi_arch[1:]], activation_fn)
            width = ([joined, *pi_arch[1:]])[-1]
        self.score_head = nn.Linear(width, 1)
        self.critic_encoder = _mlp([n_features, *vf_arch], activation_fn)
        self.latent_dim_pi = n_candidates
        self.latent_dim_vf = 2 * vf_arch[-1] + summary

    def _split(self, packed: th.Tensor) -> tuple[th.Tensor, th.Tensor, th.Tensor | None]:
        bits = 2 if self.failed else 1
        rows = packed.reshape(packed.shape[0], self.n_candidates, self.n_features + bits)
        features, mask = rows[..., : self.n_features], rows[..., self.n_features]
        return features, mask, (rows[..., -1] if self.failed else None)

    def failure_summary(self, features: th.Tensor, failed: th.Tensor) -> th.Tensor:
        """``(B, 2H + 1)``: masked mean and max of the failed candidates' embeddings, and how
        many failed (zeros before any failure); the same whatever the slots' order."""
        pooled = masked_pool(self.failure_encoder(features), failed)
        return th.cat([pooled, (failed > 0.5).sum(dim=1, keepdim=True).float()], dim=-1)

    def _scorer_input(self, features: th.Tensor, failed: th.Tensor | None) -> th.Tensor:
        """Each candidate's features, joined with what failed when the observation says it."""
        if failed is None:
            return features
        summary = self.failure_summary(features, failed)
        return th.cat([features, summary.unsqueeze(1).expand(-1, self.n_candidates, -1)], dim=-1)

    def forward_actor(self, packed: th.Tensor) -> th.Tensor:
        """Per-candidate scores ``(B, K)`` (the categorical's logits)."""
        features, mask, failed = self._split(packed)
        inputs = self._scorer_input(features, failed)
        if self.context == "none":
            return self.score_head(self.scorer_body(inputs)).squeeze(-1)
        embedded = self.scorer_embed(inputs)
        if self.context == "pool":
            pooled = masked_pool(embedded, mask).unsqueeze(1).expand(-1, self.n_candidates, -1)
            joined = th.cat([embedded, pooled], dim=-1)
        else:
            joined = embedded + self._attend(embedded, mask)
        return self.score_head(self.scorer_body(joined)).squeeze(-1)

    def _attend(self, embedded: th.Tensor, mask: th.Tensor) -> th.Tensor:
        """Masked self-attention over the valid slots (a row with none attends to all, and its
        scores are masked out by the policy anyway)."""
        padded = mask < 0.5
        padded = padded & ~padded.all(dim=1, keepdim=True)
        attended, _ = self.attention(embedded, embedded, embedded, key_padding_mask=padded,
                                     need_weights=False)  # fmt: skip
        return attended

    def forward_critic(self, packed: th.Tensor) -> th.Tensor:
        """Order-free summary ``(B, 2H)`` of the valid candidates (``(B, 2H + 2H' + 1)`` with
        the failure summary)."""
        features, mask, failed = self._split(packed)
        pooled = masked_pool(self.critic_encoder(features), mask)
        if failed is None:
            return pooled
        return th.cat([pooled, self.failure_summary(features, failed)], dim=-1)

    def forward(self, packed: th.Tensor) -> tuple[th.Tensor, th.Tensor]:
        return self.forward_actor(packed), self.forward_critic(packed)


def _heads(width: int) -> int:
    """:data:`ATTENTION_HEADS`, or fewer so that they divide ``width``."""
    return next(h for h in range(min(ATTENTION_HEADS, width), 0, -1) if width % h == 0)


class CandidateSetPolicy(MaskableActorCriticPolicy):
    """MaskablePPO policy that scores every candidate with the same network.

    ``net_arch`` is ``dict(pi=[...], vf=[...])`` (hidden sizes of the scorer and the critic
    encoder) or a list used for both; default ``[64, 64]``. ``context`` is how the scorer sees
    the other candidates (:data:`CONTEXTS`, see :class:`CandidateSetNetwork`). An observation
    with ``failed`` (the retry setting) is read: the failed candidates' pooled embedding enters
    every score and the value; ``read_failed=False`` ignores it (the policy then sees a failure
    only as a masked slot, as the set policy did before it read ``failed``: an ablation, and
    how a retry zip of that policy loads, with
    ``MaskablePPO.load(path, custom_objects={"policy_kwargs": {"context": ...,
    "read_failed": False}})``).
    """

    def __init__(
        self,
        observation_space: spaces.Dict,
        action_space: spaces.Space,
        lr_schedule: Schedule,
        net_arch: list[int] | dict[str, list[int]] | None = None,
        activation_fn: type[nn.Module] = nn.Tanh,
        context: Context = "none",
        read_failed: bool | None = None,
        **kwargs: Any,
    ) -> None:
        if context not in CONTEXTS:
            raise ValueError(f"context must be one of {CONTEXTS}, got {context!r}")
        self.context = context
        self.read_failed = read_failed
        n_candidates, _ = _candidate_shape(observation_space)
        if not isinstance(action_space, spaces.Discrete) or int(action_space.n) != n_candidates:
            raise ValueError(f"action space must be Discrete({n_candidates}), got {action_space}")
        kwargs.setdefault("features_extractor_class", CandidateSetExtractor)
        if kwargs["features_extractor_class"] is CandidateSetExtractor:
            kwargs["features_extractor_kwargs"] = {
                **(kwargs.get("features_extractor_kwargs") or {}), "read_failed": read_failed}
        super().__init__(
            observation_space,
            action_space,
            lr_schedule,
            net_arch=net_arch,
            activation_fn=activation_fn,
            **kwargs,
        )

    def _build_mlp_extractor(self) -> None:
        arch = self.net_arch
        pi_arch, vf_arch = (
            (list(arch.get("pi", [])), list(arch.get("vf", [])))
            if isinstance(arch, dict)
            else (list(arch), list(arch))
        )
        extractor = self.features_extractor
        self.mlp_extractor = CandidateSetNetwork(
            extractor.n_candidates,
            extractor.n_features,
            pi_arch=pi_arch,
            vf_arch=vf_arch or [64],
            activation_fn=self.activation_fn,
            context=self.context,
            failed=extractor.failed,
        ).to(self.device)

    def _get_constructor_parameters(self) -> dict[str, Any]:
        return {**super()._get_constructor_parameters(), "context": self.context,
                "read_failed": self.read_failed}

    def _build(self, lr_schedule: Schedule) -> None:
        super()._build(lr_schedule)
        # The scores are already the logits: a Linear(K, K) would mix slots and break symmetry.
        self.action_net = nn.Identity()
        if self.ortho_init:
            self.init_weights(self.mlp_extractor.score_head, gain=0.01)
        self.optimizer = self.optimizer_class(
            self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs
        )

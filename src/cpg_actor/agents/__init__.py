"""Actor-critics for PPO: the classic MLP actor and the CPG-Actor (with and without feedback)."""

from cpg_actor.agents.base import ActorOutput, ActStep, Agent, AgentConfig, mlp
from cpg_actor.agents.cpg_actor import CPGActorAgent
from cpg_actor.agents.mlp import MLPAgent
from cpg_actor.agents.registry import AGENTS, AgentSpec, get_agent_spec, register_agent

__all__ = [
    "AGENTS",
    "ActStep",
    "ActorOutput",
    "Agent",
    "AgentConfig",
    "AgentSpec",
    "CPGActorAgent",
    "MLPAgent",
    "get_agent_spec",
    "mlp",
    "register_agent",
]

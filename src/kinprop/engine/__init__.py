"""The engine: a mechanism compiled once into a flat model, with the by-address API."""

from kinprop.engine.engine import BatchSolution, Engine, JointFrames, Kinematics, Solution, State, Status, compile

__all__ = ["BatchSolution", "Engine", "JointFrames", "Kinematics", "Solution", "State", "Status", "compile"]

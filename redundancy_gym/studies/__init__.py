"""Reproductions of the monograph's figures: the fig. 5.10 point-to-point move (:mod:`.point_to_point`), the
kinematic IKD study of figs. 5.21-5.27 (:mod:`.ikd_study`), walking (:mod:`.walking_plots`), obstacle
(:mod:`.obstacle_plots`) and predictive-IK figures (:mod:`.predictive_figures`)."""

from .exceptions import StudyError

__all__ = ["StudyError"]

"""The test protocols a trained network is evaluated under. Each names itself, labels its rows and
says what it does (`sources.Source.actor` plays it); a protocol is read by its name here and
nowhere else."""
from __future__ import annotations

import dataclasses
import pathlib


@dataclasses.dataclass(frozen=True)
class Protocol:
  name: str
  description: str
  learns: bool = False  # every run takes one SGD step after each action (`runner.Online`)
  no_repeat: bool = False  # a run never repeats a failed action while nothing has changed
  # Wall time per case run over the frozen protocol's on a 2-core CPU (online: 1.9-2.7,
  # benchmarks/online_eval.py).
  cost: float = 1.0

  @property
  def greedy(self) -> bool:
    """Whether the trained network acts as it was trained, greedily (the frozen protocol)."""
    return not (self.learns or self.no_repeat)

  def label(self, row: str) -> str:
    """A results row's label: the policy's, marked with the protocol unless it is frozen."""
    return labelled(row, self.name)

  def folder(self, out: pathlib.Path) -> pathlib.Path:
    """Where a reproduction writes this protocol's tables: `out` for the frozen one, else
    OUT/NAME."""
    return out if self.name == FROZEN.name else out / self.name


FROZEN = Protocol('frozen', 'the trained network, frozen, acts greedily in every run')
ONLINE = Protocol('online', 'every run starts from the trained network and takes one SGD step '
                  'after each of its actions (VPG\'s and the MV-COBA authors\' test protocol)',
                  learns=True, cost=2.3)
NO_REPEAT = Protocol('no-repeat', 'the trained network, frozen, never repeats a failed action of '
                     'its run while nothing has changed (its next best one instead)',
                     no_repeat=True)
PROTOCOLS = {p.name: p for p in (FROZEN, ONLINE, NO_REPEAT)}
PAPER = (FROZEN, ONLINE)  # the paper's two: what mvcoba-reproduce runs


def labelled(row: str, name: str | None) -> str:
  """`row` marked with the protocol `name` of its settings (None: results written before rows
  recorded one, all frozen)."""
  return row if name in (None, FROZEN.name) else f'{row} [{name}]'

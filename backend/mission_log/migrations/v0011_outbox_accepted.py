"""Issue 24 (a relayed override): the soft violations the relaying console's operator
accepted, on each outbox row (a JSON list of ``[check, param]``; null on a row without an
override). The console holding the transmitter lets the override cover those only: a
violation of its own, stricter limits goes back to that operator to accept or not.
"""

from __future__ import annotations

import sqlalchemy as sa
from alembic import op

revision = "0011"
down_revision = "0010"


def upgrade() -> None:
    op.add_column("outbox", sa.Column("accepted", sa.Text))

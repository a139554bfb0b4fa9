# Copyright 2026 The trajplan_ros Authors
# SPDX-License-Identifier: Apache-2.0
"""A URDF that a parser must refuse: the billion laughs (entities that expand to gigabytes)."""

__all__ = ['BILLION_LAUGHS']

BILLION_LAUGHS = '<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol">' + ''.join(
    f'<!ENTITY lol{i + 1} "{("&lol" + (str(i) if i else "") + ";") * 10}">' for i in range(9)
) + ']><robot name="r"><link name="&lol9;"/></robot>'

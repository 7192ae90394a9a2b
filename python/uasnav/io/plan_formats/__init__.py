"""One module per mission-plan format; :mod:`uasnav.io.plans` picks one by extension.

========================== ============================================ ===================
extension                  module                                       reader / writer
========================== ============================================ ===================
``.plan``                  :mod:`~uasnav.io.plan_formats.qgc`           QGroundControl JSON
``.waypoints`` ``.txt``    :mod:`~uasnav.io.plan_formats.wpl`           QGC WPL 110
``.csv``                   :mod:`~uasnav.io.plan_formats.csv_plan`      uasnav plan CSV
``.kml``                   :mod:`~uasnav.io.plan_formats.kml`           KML LineString/Points
``.geojson``               :mod:`~uasnav.io.plan_formats.geojson`       GeoJSON LineString/Points
========================== ============================================ ===================
"""

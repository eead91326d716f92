"""What comes out: a radio map and its builder, maps in time and at several flight levels, their
GeoTIFF form, figures and the map cache. Built from a [`scene`][rainuav.radio.scene] by the
[`engines`][rainuav.radio.engines]."""

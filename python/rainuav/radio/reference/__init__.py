"""The reference the engines are measured against: a full ray tracer (Sionna RT) on the same
geometry, antennas and ground ([`tracer`][rainuav.radio.reference.tracer]), its test scenes
([`tracer_scenes`][rainuav.radio.reference.tracer_scenes]) and the wedge diffraction coefficient
it runs with ([`tracer_wedge`][rainuav.radio.reference.tracer_wedge]). Reads the scene, runs the
engines through their maps; nothing below it imports it."""



def test_a_moving_camera_has_its_small_shifts_compensated_too(textured):
    stab = Stabilizer(StabilizeConfig(min_motion=1.0))
    stab.apply(textured)
    # a fixed camera's 0.5 px is left alone ...
    assert stab.apply(_moved(textured, _similarity(0.5, 0.0))).transform is None
    # ... but once the camera has moved 3 px, a 0.5 px shift is warped as well
    assert stab.apply(_moved(textured, _similarity(3.0, 0.0))).transform is not None
    small = stab.apply(_moved(textured, _similarity(0.5, 0.0)))
    assert small.transform is not None and small.step is not None

"""Q-DAS AQDEF (.dfq): the exchange format SPC systems import; writer and reader."""

from ursim_core.datasets import dataset_root
from ursim_core.matching import experiments as ex, MatchConfig, M_GRID
c = ex.kth_pairs(dataset_root(), pipeline="released")
for label, cfg in {"released": MatchConfig.released(), "rot min": MatchConfig.released(rotation_search="min"), "own std": MatchConfig.released(standardise="own"), "paper disp": MatchConfig.released(disparity="paper")}.items():
    s = ex.summarise(ex.f1_table(c, cfg, M_GRID, legacy="fnfix"))
    print(label, round(s["malcolm"]["oracle"][0], 3), round(s["vasiliki"]["oracle"][0], 3))
